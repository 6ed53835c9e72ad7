"""Labelled results of a dynamic run, with CSV and binary (.npz) export.

Columns of the CSV: `t` (s), then per machine k (number as in the
data) `speed_pu.G<k>`, `angle_rad.G<k>` (absolute, synchronous frame, as PSTess),
`pelect_pu.G<k>` (system base), `pmech_pu_mbase.G<k>` (machine base, as its name says),
`efd_pu.G<k>`, `qelect_pu.G<k>` (system base: PSS/E's QELEC), per bus n `vmag_pu.B<n>`,
`vang_rad.B<n>`, per storage device d `pesd_pu.D<d>` (+ absorbs), and per converter c
`pibr_pu.C<c>`, `qibr_pu.C<c>` (injected P, Q on the system base).
"""

from __future__ import annotations

import os
import zipfile
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path

import numpy as np

from stabctl.dynamics.coi import coi_angle, coi_speed
from stabctl.dynamics.partition import (
    Partition,
    judged_relative,
    relative_to_islands,
    stage_at,
)
from stabctl.errors import InputError, WrongTypeError, is_number, is_whole_number
from stabctl.parallel import atomic_write

#: the `Partition` fields written to a .npz (`SimulationResult.to_npz`), in its order
PARTITION_FIELDS = ("t_s", "island", "inertia", "judged", "tripped")

#: the unit of each array `SimulationResult.to_npz` writes (its ``units`` array, "name:
#: unit" strings); the class docstring's Attributes say the same
NPZ_UNITS = {
    "t": "s",
    "speed": "pu (1 = synchronous)",
    "angle": "rad (synchronous frame)",
    "pelect": "pu on the system base",
    "qelect": "pu on the system base",
    "pmech": "pu on the machine base",
    "efd": "pu",
    "vmag": "pu",
    "vang": "rad",
    "inertia": "COI weight, MW s (H * MVA; an island with an infinite bus: 1 for it, 0 "
    "for the others, stabctl.dynamics.coi.coi_inertia)",
    "pesd": "pu on the system base (+ absorbs)",
    "ibr_p": "pu on the system base",
    "ibr_q": "pu on the system base",
    "verdict": "[stable (1/0), t_separation s or NaN]",
    "partition_t_s": "s",
    "end_vmag": "pu (every bus's at the run's end, a run recording no voltages)",
}

SERIES = ("speed", "angle", "pelect", "pmech", "efd", "qelect")
SERIES_UNITS = {
    "speed": "speed_pu",
    "angle": "angle_rad",
    "pelect": "pelect_pu",
    "pmech": "pmech_pu_mbase",
    "efd": "efd_pu",
    "qelect": "qelect_pu",
}


#: the verdict of a run that lost synchronism (`SimulationResult.verdict`)
LOSS_OF_SYNCHRONISM = "loss of synchronism"
#: the verdict of a run whose events left no machine in service (`de_energised_at`)
DE_ENERGISED = "de-energised"
#: the verdict of a run its monitor ended before its end without a separation
#: (`stabctl.dynamics.driver.Simulator.run`'s `monitor`; its own word in
#: ``meta["early_verdict"]``): undecided
STOPPED = "stopped by its monitor"


def de_energised_at(partitions, t_end: float) -> float | None:
    """The start of the first stage, up to `t_end`, in which no machine is judged (every
    machine tripped, or none left in the main grid of its island: the customers lost).

    Parameters
    ----------
    partitions : sequence of Partition
        A run's partitions (`stabctl.dynamics.partition`); empty: never.
    t_end : float
        The run's last recorded time, s.

    Returns
    -------
    float or None
        The stage's start, s; None when some machine is judged throughout.
    """
    for p in partitions:
        if p.t_s <= t_end and not np.any(p.judged):
            return float(p.t_s)
    return None


#: `SimulationResult.end_concerns`: a bus voltage below this at the end of a stable run
#: is no normal operating point (pu; the storage controllers' voltage gate, and the
#: lowest voltage the recovery criteria of planning studies accept after a fault)
END_VOLTAGE_PU = 0.8
#: and a frequency further than this from nominal (Hz; NERC PRC-024's band of
#: continuous operation, 59.4-60.6 Hz at 60 Hz)
END_FREQUENCY_HZ = 0.6
#: `SimulationResult.drift`: a run without disturbance whose machine speed, field voltage
#: or bus voltage moves further than this from its start (pu) is not at rest (PSS/E
#: practice: a no-disturbance run stays flat well within 1e-4 pu)
FLAT_DRIFT_PU = 1e-4


def _whole(number, what: str) -> None:
    """Refuse a `SimulationResult.machine` / `bus` number that is not a whole number: text
    ('1') was looked up and reported 'not in the result'."""
    if not is_whole_number(number):
        raise WrongTypeError(f"SimulationResult.{what}(number): a {what} number, got {number!r}")


@dataclass
class SimulationResult:
    """Trajectories of one run (`Simulator.run`), per machine, bus and storage device.

    n_t is the number of recorded times (the integration grid, which lands on every event
    time; a time appears twice only around a zero-length interval, e.g. a fault cleared at
    both ends at the same instant, as PSTess), n_mac the number of machines, n_bus
    of buses, n_dev of storage devices.
    The loss-of-synchronism verdict uses the centre of inertia (paper eq. 40, weights
    `inertia`) of each machine's island (`island`; one in a connected network); once a
    run's events trip machines or cut islands apart, that of each stage's islands, judging
    only the machines in service in the main grid (`partitions`,
    `stabctl.dynamics.partition`).

    Attributes
    ----------
    t : ndarray, shape (n_t,)
        Times, s, non-decreasing, from 0 to the end of the run (or its stop).
    machines : ndarray of int, shape (n_mac,)
        Machine numbers as in the data, the column order of the per-machine arrays.
    buses : ndarray of int, shape (n_bus,)
        Bus numbers as in the data, the column order of `vmag` and `vang`.
    speed : ndarray, shape (n_t, n_mac)
        Rotor speeds, pu (1 = synchronous).
    angle : ndarray, shape (n_t, n_mac)
        Rotor angles, rad, absolute (synchronous reference frame, as PSTess).
    pelect : ndarray, shape (n_t, n_mac)
        Electrical power, pu on the system base.
    pmech : ndarray, shape (n_t, n_mac)
        Mechanical power, pu on the machine base.
    efd : ndarray, shape (n_t, n_mac)
        Field voltage, pu.
    vmag : ndarray, shape (n_t, n_bus)
        Bus voltage magnitudes, pu.
    vang : ndarray, shape (n_t, n_bus)
        Bus voltage angles, rad.
    inertia : ndarray, shape (n_mac,)
        COI weights per machine: H * MVA, MW s (MJ); with an infinite bus in an island, 1
        for it and 0 for the island's other machines (`stabctl.dynamics.coi.coi_inertia`).
    island : ndarray of int, shape (n_mac,), optional
        Each machine's island in the network before the disturbance
        (`stabctl.network.topology.machine_islands`); default all 0 (connected).
    devices : ndarray of int, shape (n_dev,), optional
        Storage device numbers (1, 2, ... in the fleet's order); empty (default) without
        storage.
    pesd : ndarray, shape (n_t, n_dev), or None, optional
        Storage device powers, pu on the system base (+ absorbs): the power the network
        takes (0 while a device's bus is below the 0.5 pu low-voltage switch, whatever its
        law commands; a WECC battery's converter power); None (default) without storage.
    converters : ndarray of int, shape (n_ibr,), optional
        Converter numbers as in the data (``ibr_con``), the column order of `ibr_p` and
        `ibr_q`; empty (default) without converters.
    ibr_p, ibr_q : ndarray, shape (n_t, n_ibr), or None, optional
        Active and reactive power the converters inject, pu on the system base; None
        (default) when not recorded.
    stable : bool, optional
        False when some rotor angle left the COI by more than the separation limit
        (`Simulator.run`, default pi rad), or when the run's events left no machine in
        service in the main grid (`de_energised_s`: a blackout is no stable outcome);
        default True.
    t_separation : float or None, optional
        First recorded time the limit was exceeded, s; None (default) if never.
    separated : list of int, optional
        Numbers of the machines that lost synchronism (the smaller coherent group,
        `stabctl.dynamics.driver.separated_group`); empty (default) if none.
    meta : dict, optional
        Run description: ``case``, ``conventions``, ``wall_time_s`` (s),
        ``max_initial_derivative`` (the largest absolute derivative at t = 0 over the
        states, in its state's unit per s: pu/s, rad/s) and
        ``max_initial_derivative_state`` (that state's name, e.g. ``exc.Efd.G3``), and
        with storage ``switchings`` (the
        switching log, see `switching_records`) and ``storage`` (per-device figures:
        switchings, chattering, energy absorbed / delivered in MJ, peak power in MW); with
        islanding ``islanded`` (per stage: buses cut from every machine with the load
        shed, or an island apart from the main grid with its buses and machines,
        `stabctl.dynamics.driver.islanding_log`) and with machines tripped ``tripped``
        (per stage: time and machine numbers).
    partitions : tuple of Partition, optional
        The machines' islands stage by stage (`stabctl.dynamics.partition.Partition`)
        when the run trips machines or splits an island; empty (default) otherwise, every
        machine then judged against `island`'s COI throughout.
    qelect : ndarray, shape (n_t, n_mac), optional
        Reactive power out of each machine, pu on the system base (PSS/E's QELEC); None
        (default) for a result made otherwise than by a run (a test's, a file written
        before it was kept).
    """

    t: np.ndarray
    machines: np.ndarray
    buses: np.ndarray
    speed: np.ndarray
    angle: np.ndarray
    pelect: np.ndarray
    pmech: np.ndarray
    efd: np.ndarray
    vmag: np.ndarray
    vang: np.ndarray
    inertia: np.ndarray
    island: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    devices: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    pesd: np.ndarray | None = None
    converters: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    ibr_p: np.ndarray | None = None
    ibr_q: np.ndarray | None = None
    stable: bool = True
    t_separation: float | None = None
    separated: list = field(default_factory=list)
    meta: dict = field(default_factory=dict)
    partitions: tuple[Partition, ...] = ()
    qelect: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.island.size == 0:
            self.island = np.zeros(self.machines.size, int)

    @property
    def de_energised_s(self) -> float | None:
        """When the run's events left no machine that the criterion judges (every machine
        tripped, or cut off from the load of the main grid: `de_energised_at`), s; None
        if never."""
        return de_energised_at(self.partitions, float(self.t[-1]) if self.t.size else 0.0)

    @property
    def verdict(self) -> str:
        """The run's verdict, a label: ``"stable"``, ``"loss of synchronism"`` (some rotor
        angle left the COI by more than the limit: `t_separation`), ``DE_ENERGISED``
        (no machine left in service: `de_energised_s`) or ``STOPPED`` (ended by a run
        monitor before its end, neither of those seen by then: undecided)."""
        if self.t_separation is not None:
            return LOSS_OF_SYNCHRONISM
        if self.de_energised_s is not None:
            return DE_ENERGISED
        if self.stable and "early_verdict" in self.meta:
            return STOPPED
        return "stable" if self.stable else LOSS_OF_SYNCHRONISM

    # -- centre of inertia (paper eq. 40) ----------------------------------------------
    @property
    def coi_angle(self) -> np.ndarray:
        """Inertia-weighted mean rotor angle (rad), shape (n_t,), over every machine (the
        system's COI in a connected network; per island: `relative_angle`)."""
        return coi_angle(self.angle, self.inertia)

    @property
    def coi_speed(self) -> np.ndarray:
        """Inertia-weighted mean speed (pu), shape (n_t,), over every machine (the
        system's COI in a connected network; per island: `relative_speed`)."""
        return coi_speed(self.speed, self.inertia)

    @property
    def relative_angle(self) -> np.ndarray:
        """delta_i - delta_COI of machine i's island (rad), shape (n_t, n_mac): what the
        loss-of-synchronism verdict judges (with `partitions`, the island of the stage at
        each time; 0 for a tripped machine)."""
        return relative_to_islands(self.angle, self.t, self.inertia, self.island, self.partitions)

    @property
    def relative_speed(self) -> np.ndarray:
        """omega_i - omega_COI of machine i's island (pu), shape (n_t, n_mac): what a
        storage device's controller acts on (with `partitions`, as the simulator's
        controllers, the island of the stage at each time; 0 for a tripped machine)."""
        return relative_to_islands(self.speed, self.t, self.inertia, self.island, self.partitions)

    @property
    def max_angle_from_coi(self) -> float:
        """Largest abs(delta_i - delta_COI) over the run, each machine against its
        island's COI (rad); with `partitions`, over the machines the criterion judges
        (`judged_angle`)."""
        if not self.partitions:
            return float(np.max(np.abs(self.relative_angle)))
        return float(np.max(self.judged_angle))

    @property
    def judged_angle(self) -> np.ndarray:
        """abs(delta_i - delta_COI) of the machines the loss-of-synchronism criterion
        judges (rad), shape (n_t, n_mac), 0 for the others (tripped, or islanded apart from
        the main grid: `stabctl.dynamics.partition.judged_relative`)."""
        args = (self.angle, self.t, self.inertia, self.island, self.partitions)
        return np.abs(judged_relative(*args))

    @property
    def judged(self) -> np.ndarray:
        """The machines the criterion judges at the end of the run, bool (n_mac,): every
        machine without `partitions`."""
        last = self.last_partition()
        return np.ones(self.machines.size, bool) if last is None else last.judged.copy()

    def ran_away(self, case, q: int, value: float, t: float) -> bool:
        """Whether a run stopped by the integrator's speed band (state q, its value, at t
        s) ended in a machine that had already lost synchronism running away (no governor
        holds a slipping machine).  Then the run's verdict, loss of synchronism, stands:
        ``meta["runaway"]`` says where it stopped, and the caller returns this result
        instead of raising a NumericalInstabilityError that blamed the step (round 58
        BA99-100: the five-bus case cleared late separated at 1.47 s, ran to 10.4 s and
        failed with "use a smaller step" at every step and with both methods).

        Parameters
        ----------
        case : Case
            The case run.
        q : int
            The state the speed band stopped the run at (machine speeds are states n_mac
            to 2 n_mac - 1).
        value : float
            Its value, pu speed.
        t : float
            The end of the failing step, s.

        Returns
        -------
        bool
        """
        from stabctl.dynamics.integrator import SPEED_BAND

        nm = case.machines.number.size
        if not (nm <= q < 2 * nm and np.isfinite(value)) or self.stable:
            return False
        number = int(case.machines.number[q - nm])
        if number not in self.separated:
            return False
        self.meta["runaway"] = (
            f"{case.machine_name(number)}, separated, ran past {SPEED_BAND:g} pu from "
            f"synchronous speed ({value:.3g} pu) at t = {t:.4f} s: the run stopped there"
        )
        return True

    def drift(self) -> dict:
        """The largest move from the run's start of a machine speed, field voltage or bus
        voltage magnitude: what a run without disturbance (a flat run) must keep within
        `FLAT_DRIFT_PU` (an equilibrium that is not stable drifts away from round-off on,
        though every derivative is 0 at the start).

        Returns
        -------
        dict
            ``pu`` (the move, pu), ``quantity`` ('speed', 'efd' or 'vmag'), ``where``
            (machine or bus number), ``t_s`` (when, s); ``pu`` 0 and ``where`` None for
            a run that moved nothing.
        """
        best: dict = {"pu": 0.0, "quantity": "speed", "where": None, "t_s": 0.0}
        for quantity, values, numbers in (
            ("speed", self.speed, self.machines),
            ("efd", self.efd, self.machines),
            ("vmag", self.vmag, self.buses),
        ):
            if values is None or values.size == 0:
                continue
            moves = np.abs(values - values[0])
            k, j = np.unravel_index(int(np.nanargmax(moves)), moves.shape)
            if moves[k, j] > best["pu"]:
                best = {
                    "pu": float(moves[k, j]),
                    "quantity": quantity,
                    "where": int(numbers[j]),
                    "t_s": float(self.t[k]),
                }
        return best

    def end_state(self, freq_hz: float) -> dict:
        """Where the run ends: its time, the lowest bus voltage among the energised buses
        (above 1e-3 pu: a de-energised island's are 0) and its bus, and the frequency of
        the machines the criterion judges at the end (their inertia-weighted speed times
        `freq_hz`).  A run stable by the angle criterion may end far from a normal
        operating point (an area tripped off: the rest at 0.6 pu and 58.7 Hz), which
        these show.  A run that records no bus voltage (a CCT search's,
        `stabctl.dynamics.driver.Simulator.run` ``voltages=False``) gives every bus's at
        its end all the same (``meta`` ``end_vmag``, ``end_buses``).

        Parameters
        ----------
        freq_hz : float
            The case's nominal frequency, Hz.

        Returns
        -------
        dict
            ``t_s``, ``lowest_voltage_pu``, ``lowest_voltage_bus`` (None without an
            energised bus), ``frequency_hz`` (None without a judged machine).

        Raises
        ------
        InputError
            `freq_hz` not a number in [1, 1000] Hz (a case's range).
        """
        if not (is_number(freq_hz) and 1 <= freq_hz <= 1000):  # (round 45: nan, 0, -60 ran)
            raise InputError(f"end_state(freq_hz): a frequency in [1, 1000] Hz, got {freq_hz!r}")
        v, buses = self.vmag[-1] if self.vmag.size else np.zeros(0), self.buses
        if not v.size and self.meta.get("end_vmag") is not None:  # a run recording none
            v, buses = self.meta["end_vmag"], self.meta["end_buses"]
        on = np.flatnonzero(v > 1e-3)
        k = int(on[np.argmin(v[on])]) if on.size else None
        judged = self.judged & (self.inertia > 0)
        speed = (
            float(self.speed[-1, judged] @ self.inertia[judged] / self.inertia[judged].sum())
            if judged.any()
            else None
        )
        return {
            "t_s": float(self.t[-1]),
            "lowest_voltage_pu": None if k is None else float(v[k]),
            "lowest_voltage_bus": None if k is None else int(buses[k]),
            "frequency_hz": None if speed is None else speed * freq_hz,
        }

    def end_concerns(self, freq_hz: float) -> list[str]:
        """What of `end_state` is no normal operating point: a bus below
        `END_VOLTAGE_PU`, a frequency more than `END_FREQUENCY_HZ` from `freq_hz`; one
        phrase each, empty when neither (or the run is not stable).

        Parameters
        ----------
        freq_hz : float
            The case's nominal frequency, Hz.

        Returns
        -------
        list of str
        """
        if not self.stable:
            return []
        end = self.end_state(freq_hz)
        out = []
        v = end["lowest_voltage_pu"]
        if v is not None and v < END_VOLTAGE_PU:
            out.append(f"bus {end['lowest_voltage_bus']} at {v:.3f} pu")
        f = end["frequency_hz"]
        if f is not None and abs(f - freq_hz) > END_FREQUENCY_HZ:
            out.append(f"the machines it judges at {f:.2f} Hz")
        return out

    def last_partition(self) -> Partition | None:
        """The partition of the last recorded time (`partitions`).

        Returns
        -------
        Partition or None
            None without partitions.
        """
        if not self.partitions:
            return None
        t = self.t[-1:] if self.t.size else np.zeros(1)
        return self.partitions[int(stage_at(t, self.partitions)[0])]

    def speed_at(self, t: np.ndarray | float) -> np.ndarray:
        """Rotor speeds at given times, by linear interpolation in the trajectory.

        Parameters
        ----------
        t : ndarray, shape (n,), or float
            Times, s, within ``[t[0], t[-1]]`` (outside: the end values).

        Returns
        -------
        ndarray, shape (n, n_mac), or (n_mac,) for one time given as a number
            Speeds, pu; at a time recorded twice (a zero-length interval) the value
            after it.

        Raises
        ------
        InputError
            `t` not finite numbers (a text, None, NaN, an array of two or more axes).
        """
        try:
            times = None if isinstance(t, str) else np.asarray(t, float)
        except (TypeError, ValueError):  # (round 45: numpy's casting errors)
            times = None
        if times is None or times.ndim > 1 or not np.all(np.isfinite(times)):
            raise InputError(f"speed_at(t): finite times in s (a number or a 1-D array), got {t!r}")
        if times.ndim == 0:
            return self.speed_at(np.atleast_1d(times))[0]
        t = times
        keep = np.r_[np.diff(self.t) > 0, True]
        return np.stack(
            [np.interp(t, self.t[keep], self.speed[keep, k]) for k in range(self.speed.shape[1])],
            axis=1,
        )

    def machine(self, number: int) -> int:
        """Column index of a machine in the per-machine arrays.

        Parameters
        ----------
        number : int
            Machine number as in the data.

        Returns
        -------
        int
            0-based column of `speed`, `angle`, `pelect`, `pmech`, `efd`.

        Raises
        ------
        KeyError
            The machine is not in the result; the message names it.
        WrongTypeError
            `number` not a whole number (``'1'``: text).
        """
        _whole(number, "machine")
        hit = np.nonzero(self.machines == number)[0]
        if hit.size == 0:
            raise KeyError(f"machine {number} is not in the result")
        return int(hit[0])

    def bus(self, number: int) -> int:
        """Column index of a bus in `vmag` and `vang`.

        Parameters
        ----------
        number : int
            Bus number as in the data.

        Returns
        -------
        int
            0-based column of `vmag` and `vang`.

        Raises
        ------
        KeyError
            The bus is not in the result; the message names it.
        WrongTypeError
            `number` not a whole number (``'1'``: text).
        """
        _whole(number, "bus")
        hit = np.nonzero(self.buses == number)[0]
        if hit.size == 0:
            raise KeyError(f"bus {number} is not in the result")
        return int(hit[0])

    def summary(self) -> dict:
        """Verdict and figures, as the CLI prints them with ``--json``.

        Returns
        -------
        dict
            ``stable`` (bool; None for a run its monitor stopped undecided, `STOPPED`),
            ``verdict`` (`verdict`), ``de_energised_s`` (s or None),
            ``t_separation_s`` (s or None), ``separated_machines``
            (machine numbers), ``max_angle_from_coi_rad`` (largest abs(delta_i - delta_COI),
            rad), ``t_end_s`` (last recorded time, s), ``n_steps`` (the intervals of
            positive length: a zero-length interval, its time recorded twice, is no step;
            a line fault cleared at both ends at once was "1201 steps" for 6 s at 5 ms),
            then every entry of `meta` but its trajectories (arrays, e.g. the WECC
            batteries' ``pesd_command``: in `meta`, not in a summary).
        """
        verdict = self.verdict
        return {
            "stable": None if verdict == STOPPED else self.stable,
            "verdict": verdict,
            "de_energised_s": self.de_energised_s,
            "t_separation_s": self.t_separation,
            "separated_machines": [int(m) for m in self.separated],
            "max_angle_from_coi_rad": self.max_angle_from_coi,
            "t_end_s": float(self.t[-1]),
            "n_steps": int(np.count_nonzero(np.diff(self.t) > 0)),
            **{k: v for k, v in self.meta.items() if not isinstance(v, np.ndarray)},
        }

    def switching_records(self) -> list[dict]:
        """The storage switching log as records with named fields.

        Returns
        -------
        list of dict
            One record per row (t, device, mode, relative speed) of
            ``meta["switchings"]``, in time order: ``t_s`` (s), ``device`` (number),
            ``bus`` and ``machine`` of the device when known (else None), ``mode``
            ("absorb", "idle", "inject", or the commanded set-point in units of the
            rating as text), ``mode_code`` (+1, 0, -1, or that set-point) and
            ``rel_speed_hz`` (the device's machine speed minus the COI speed seen by its
            controller, Hz).  Empty without storage.
        """
        info = {int(d["device"]): d for d in self.meta.get("storage", [])}
        names = {1: "absorb", 0: "idle", -1: "inject"}
        out = []
        for t, dev, mode, rel in self.meta.get("switchings", []):
            d, m = info.get(int(dev), {}), float(mode)
            code = int(m) if m.is_integer() else m
            out.append(
                {
                    "t_s": float(t),
                    "device": int(dev),
                    "bus": d.get("bus"),
                    "machine": d.get("machine"),
                    "mode": names.get(code, f"{m:g}"),
                    "mode_code": code,
                    "rel_speed_hz": float(rel),
                }
            )
        return out

    # -- export -------------------------------------------------------------------------
    def columns(self) -> tuple[list[str], np.ndarray]:
        """CSV header and data matrix (column names in the module docstring).

        Returns
        -------
        names : list of str
            Column names, n_columns = 1 + 6 n_mac + 2 n_bus (+ n_dev with storage, + 2
            n_ibr with converters; 5 n_mac without `qelect`): ``t``, then
            ``speed_pu.G<k>``, ``angle_rad.G<k>``, ``pelect_pu.G<k>``,
            ``pmech_pu_mbase.G<k>``, ``efd_pu.G<k>``, ``qelect_pu.G<k>`` per machine k,
            ``vmag_pu.B<n>`` and ``vang_rad.B<n>`` per bus n, ``pesd_pu.D<d>`` per device
            d, ``pibr_pu.C<c>`` then ``qibr_pu.C<c>`` per converter c (injected, system
            base).
        data : ndarray, shape (n_t, n_columns)
            The values, units as in the names (s, pu, rad).
        """
        names, blocks = ["t"], [self.t[:, None]]
        for s in SERIES:
            if getattr(self, s) is None:  # qelect of a result not from a run
                continue
            names += [f"{SERIES_UNITS[s]}.G{int(k)}" for k in self.machines]
            blocks.append(getattr(self, s))
        names += [f"vmag_pu.B{int(n)}" for n in self.buses]
        names += [f"vang_rad.B{int(n)}" for n in self.buses]
        blocks += [self.vmag, self.vang]
        if self.pesd is not None and self.devices.size:
            names += [f"pesd_pu.D{int(d)}" for d in self.devices]
            blocks.append(self.pesd)
        if self.ibr_p is not None and self.ibr_q is not None and self.converters.size:
            names += [f"pibr_pu.C{int(c)}" for c in self.converters]
            names += [f"qibr_pu.C{int(c)}" for c in self.converters]
            blocks += [self.ibr_p, self.ibr_q]
        return names, np.hstack(blocks)

    def to_csv(self, path: str | os.PathLike) -> Path:
        """Write the trajectories as CSV (`columns`; 10 significant digits), atomically
        (temporary file beside it, then rename).

        Parameters
        ----------
        path : str or os.PathLike
            The CSV file; its directory is created if missing.

        Returns
        -------
        Path
            `path`.
        """
        names, data = self.columns()
        return atomic_write(
            path,
            lambda f: np.savetxt(
                f, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g"
            ),
        )

    def to_npz(self, path: str | os.PathLike) -> Path:
        """Write every array and the verdict to a compressed .npz, atomically (temporary
        file beside it, then rename); `meta` is not written except a run monitor's
        ``early_verdict`` (array ``early_verdict``: a stopped run reads back `STOPPED`,
        not stable) and a run's end voltages where it recorded none (``end_vmag``,
        ``end_buses``: `end_state` reads them back), `partitions` (if any) as one
        array per field (``partition_t_s``, ``partition_island``, ...); ``units`` holds
        each array's unit as "name: unit" strings (`NPZ_UNITS`).

        Parameters
        ----------
        path : str or os.PathLike
            The .npz file; its directory is created if missing.

        Returns
        -------
        Path
            `path`.
        """
        arrays = {k: v for k, v in self.__dict__.items() if isinstance(v, np.ndarray)}
        if not self.converters.size:  # files of cases without converters as before
            arrays.pop("converters", None)
        arrays["verdict"] = np.array([self.stable, self.t_separation or np.nan], float)
        arrays["separated"] = np.asarray(self.separated, int)
        if "early_verdict" in self.meta:  # a run its monitor stopped (files of others as before)
            arrays["early_verdict"] = np.array(str(self.meta["early_verdict"]))
        if not self.vmag.size and self.meta.get("end_vmag") is not None:  # voltages=False
            arrays["end_vmag"] = np.asarray(self.meta["end_vmag"], float)
            arrays["end_buses"] = np.asarray(self.meta["end_buses"], int)
        if self.partitions:  # files of runs without trips or splits as before
            for name in PARTITION_FIELDS:
                arrays[f"partition_{name}"] = np.array([getattr(p, name) for p in self.partitions])
        arrays["units"] = np.array([f"{k}: {NPZ_UNITS[k]}" for k in arrays if k in NPZ_UNITS])
        return atomic_write(path, lambda f: np.savez_compressed(f, **arrays), mode="wb")

    @classmethod
    def from_npz(cls, path: str | os.PathLike) -> SimulationResult:
        """Read a result written by `to_npz`.

        Parameters
        ----------
        path : str or os.PathLike
            The .npz file.

        Returns
        -------
        SimulationResult
            The arrays and verdict as written; `meta` holds only a monitor's
            ``early_verdict`` and the end voltages of a run recording none
            (``end_vmag``, ``end_buses``) if written (the rest is not stored).

        Raises
        ------
        InputError
            `path` is no npz archive (numpy's words about pickled data invited an unsafe
            load), one whose arrays unpack to more than MAX_NPZ_BYTES, one holding an
            object (pickled) array, an array `to_npz` does not write or without one it
            writes; each naming the file (and the array).
        OSError
            The file cannot be read.
        """
        d = _npz_arrays(path)
        fixed = {"stable", "t_separation", "meta", "partitions"}  # not arrays of the file
        names = {f.name for f in fields(cls)} - fixed
        known = names | {"verdict", "units", "early_verdict", "end_vmag", "end_buses"}
        known |= {f"partition_{n}" for n in PARTITION_FIELDS}
        unknown = sorted(set(d) - known)
        needed = {f.name for f in fields(cls) if _no_default(f)} | {"verdict", "separated"}
        missing = sorted(needed - set(d))
        if unknown or missing:
            raise InputError(
                f"{path}: not a result written by SimulationResult.to_npz ("
                + "; ".join(
                    t
                    for t in (
                        f"arrays it does not write: {', '.join(unknown)}" if unknown else "",
                        f"no {', '.join(missing)} array" if missing else "",
                    )
                    if t
                )
                + ")"
            )
        d.pop("units", None)  # (files written before it have none)
        _check_contents(d, path)
        early = d.pop("early_verdict", None)
        meta = {} if early is None else {"early_verdict": str(early)}
        if "end_vmag" in d:  # a run recording no voltages: its end's (end_state)
            meta["end_vmag"], meta["end_buses"] = d.pop("end_vmag"), d.pop("end_buses")
        stable, tsep = d.pop("verdict")
        sep = [int(i) for i in d.pop("separated")]  # as a run gives them: JSON-able ints
        parts = {name: d.pop(f"partition_{name}", ()) for name in PARTITION_FIELDS}
        partitions = tuple(
            Partition(float(t), island, inertia, judged.astype(bool), tripped.astype(bool))
            for t, island, inertia, judged, tripped in zip(*parts.values())
        )
        return cls(
            **d,
            stable=bool(stable),
            t_separation=None if np.isnan(tsep) else float(tsep),
            separated=sep,
            partitions=partitions,
            meta=meta,
        )


#: the bytes the arrays of a result file may unpack to (`SimulationResult.from_npz`): a
#: 20 s run of a 2000-bus case with every bus voltage is about 0.3 GB; a 2 MB file whose
#: array unpacked to 2 GiB was read whole
MAX_NPZ_BYTES = 4 << 30
#: a result file whose arrays unpack to more than this many times their packed size,
#: beyond BOMB_BYTES, is refused (deflate packs at most about 1000:1, a run's floats far
#: less): a 2 MB file of 2 GiB of zeros
BOMB_RATIO, BOMB_BYTES = 500, 256 << 20


#: the arrays of a result file with a row a time and a column a machine, bus, storage
#: device or converter (`_check_contents`): name -> the array numbering the columns
_PER_TIME = {
    **{n: "machines" for n in ("speed", "angle", "pelect", "pmech", "efd", "qelect")},
    "vmag": "buses",
    "vang": "buses",
    "pesd": "devices",
    "ibr_p": "converters",
    "ibr_q": "converters",
}


def _check_contents(d: dict, path) -> None:
    """InputError naming the file and the array for contents `SimulationResult.to_npz`
    does not write (round 44: a damaged verdict or time axis raised numpy's errors, and
    arrays of the wrong width, a verdict of NaN or a time axis backwards were read as a
    run and its verdict): the verdict (stable 0 or 1, the separation time NaN or >= 0),
    a finite non-decreasing time axis, integer numbering arrays, and each per-time array
    of one row a time and one column a machine (bus, device, converter)."""

    def bad(name: str, why: str):
        raise InputError(
            f"{path}: array {name!r} {why}: not a result written by SimulationResult.to_npz"
        )

    v = d["verdict"]
    if v.shape != (2,) or v.dtype.kind != "f":
        bad("verdict", f"has shape {v.shape} and dtype {v.dtype} (two floats expected)")
    if v[0] not in (0.0, 1.0) or not (np.isnan(v[1]) or (np.isfinite(v[1]) and v[1] >= 0)):
        bad("verdict", f"holds {v.tolist()} (stable 0 or 1, then a separation time or NaN)")
    t = d["t"]
    if t.ndim != 1 or t.dtype.kind != "f" or not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0):
        bad("t", "is not a time axis (finite times, not decreasing)")
    for name in ("machines", "buses", "devices", "converters", "island", "separated", "end_buses"):
        if name in d and (d[name].ndim != 1 or d[name].dtype.kind not in "iu"):
            bad(name, f"has shape {d[name].shape} and dtype {d[name].dtype} (integers)")
    if ("end_vmag" in d) != ("end_buses" in d) or (
        "end_vmag" in d
        and (d["end_vmag"].dtype.kind != "f" or d["end_vmag"].shape != d["end_buses"].shape)
    ):
        bad("end_vmag", "is not one float a bus of end_buses")
    if "inertia" in d and d["inertia"].shape != d["machines"].shape:
        bad("inertia", f"has shape {d['inertia'].shape}, not one weight a machine")
    for name, columns in _PER_TIME.items():
        if name not in d:
            continue
        width = d[columns].size if columns in d else 0
        widths = (width, 0) if name in ("vmag", "vang") else (width,)  # voltages=False: 0
        a = d[name]
        if a.ndim != 2 or a.shape[0] != t.size or a.shape[1] not in widths:
            shape = f"({t.size}, {width})"
            bad(name, f"has shape {a.shape}, not {shape}: a row a time, a column of {columns}")


def _no_default(f) -> bool:
    """Whether a dataclass field has no default (a result file must hold its array)."""
    return f.default is MISSING and f.default_factory is MISSING


def _npz_arrays(path) -> dict:
    """The arrays of an npz result file, checked: an npz archive, its arrays' declared
    sizes within MAX_NPZ_BYTES before any is read, none an object array (a pickle: never
    loaded).  The file is opened once: the sizes checked are those of the bytes read."""
    with open(path, "rb") as fh:
        try:
            with zipfile.ZipFile(fh) as zf:
                size = sum(info.file_size for info in zf.infolist())
                packed = sum(info.compress_size for info in zf.infolist())
        except (zipfile.BadZipFile, EOFError):
            size = packed = 0
        if size > MAX_NPZ_BYTES or (size > BOMB_BYTES and size > BOMB_RATIO * packed):
            raise InputError(
                f"{path}: its arrays unpack to {size} bytes from {packed}, more than a result "
                f"file holds (at most {MAX_NPZ_BYTES} bytes, {BOMB_RATIO} times its packed "
                f"size beyond {BOMB_BYTES}): refused before reading them"
            )
        fh.seek(0)
        try:
            z = np.load(fh)
        except (ValueError, zipfile.BadZipFile, EOFError):  # numpy's words invite a pickle
            raise InputError(
                f"{path}: not a result written by SimulationResult.to_npz (not an npz archive)"
            ) from None
        if not isinstance(z, np.lib.npyio.NpzFile):
            raise InputError(
                f"{path}: not a result written by SimulationResult.to_npz (one .npy array, "
                "not an npz archive)"
            )
        return _npz_members(path, z)


def _npz_members(path, z) -> dict:
    """The arrays of an open npz archive `z` of file `path`, none an object array."""
    d = {}
    with z:
        for k in z.files:
            try:
                d[k] = z[k]
            except ValueError:  # an object array: numpy's words invite a pickle
                raise InputError(
                    f"{path}: array {k!r} holds Python objects (pickled data, never loaded): "
                    "not a result written by SimulationResult.to_npz"
                ) from None
    return d
