"""Labelled results of a dynamic run, with CSV and binary (.npz) export.

Columns of the CSV: `t` (s), then per machine k (number as in the
data) `speed_pu.G<k>`, `angle_rad.G<k>` (absolute, synchronous frame, as PSTess),
`pelect_pu.G<k>` (system base), `pmech_pu.G<k>` (machine base), `efd_pu.G<k>`, per bus n
`vmag_pu.B<n>`, `vang_rad.B<n>`, and per storage device d `pesd_pu.D<d>` (+ absorbs).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from stabctl.dynamics.coi import coi_angle, coi_speed
from stabctl.parallel import atomic_write

SERIES = ("speed", "angle", "pelect", "pmech", "efd")
SERIES_UNITS = {"speed": "speed_pu", "angle": "angle_rad", "pelect": "pelect_pu",
                "pmech": "pmech_pu", "efd": "efd_pu"}


@dataclass
class SimulationResult:
    """Trajectories of one run, shape (n_t,) for t and (n_t, n) per machine/bus/device.

    Attributes:
        t: time (s); machines, buses, devices: numbers as in the data;
        speed (pu), angle (rad), pelect (pu system base), pmech (pu machine base), efd (pu),
        vmag (pu), vang (rad), pesd (pu, + absorbs); inertia: H*MVA per machine (MJ) for
        the centre of inertia; stable, t_separation, separated: loss-of-synchronism verdict
        (machines whose angle left the COI by more than the limit), meta: run description.
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
    devices: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    pesd: np.ndarray | None = None
    stable: bool = True
    t_separation: float | None = None
    separated: list = field(default_factory=list)
    meta: dict = field(default_factory=dict)

    # -- centre of inertia (paper eq. 40) ----------------------------------------------
    @property
    def coi_angle(self) -> np.ndarray:
        """Inertia-weighted mean rotor angle (rad), shape (n_t,)."""
        return coi_angle(self.angle, self.inertia)

    @property
    def coi_speed(self) -> np.ndarray:
        """Inertia-weighted mean speed (pu), shape (n_t,)."""
        return coi_speed(self.speed, self.inertia)

    @property
    def max_angle_spread(self) -> float:
        """Largest |delta_i - delta_COI| over the run (rad)."""
        return float(np.max(np.abs(self.angle - self.coi_angle[:, None])))

    def speed_at(self, t: np.ndarray) -> np.ndarray:
        """Rotor speeds (pu) at times ``t`` (s, shape (n,)) by linear interpolation,
        shape (n, n_mac); at an event time (recorded twice) the value after it."""
        keep = np.r_[np.diff(self.t) > 0, True]
        return np.stack([np.interp(t, self.t[keep], self.speed[keep, k])
                         for k in range(self.speed.shape[1])], axis=1)

    def machine(self, number: int) -> int:
        """Column index of machine `number`; KeyError names it if absent."""
        hit = np.nonzero(self.machines == number)[0]
        if hit.size == 0:
            raise KeyError(f"machine {number} is not in the result")
        return int(hit[0])

    def bus(self, number: int) -> int:
        """Column index of bus `number`; KeyError names it if absent."""
        hit = np.nonzero(self.buses == number)[0]
        if hit.size == 0:
            raise KeyError(f"bus {number} is not in the result")
        return int(hit[0])

    def summary(self) -> dict:
        """Verdict and figures for `--json`."""
        return {"stable": self.stable, "t_separation_s": self.t_separation,
                "separated_machines": [int(m) for m in self.separated],
                "max_angle_spread_rad": self.max_angle_spread,
                "t_end_s": float(self.t[-1]), "n_steps": int(self.t.size - 1), **self.meta}

    def switching_records(self) -> list[dict]:
        """The storage switching log (`meta["switchings"]`, rows (t, device, mode,
        relative speed)) as records with named fields: `t_s` (s), `device` (number),
        `bus` and `machine` of the device when known, `mode` ("absorb", "idle",
        "inject", or the commanded set-point in units of the rating as text), `mode_code`
        (+1, 0, -1, or that set-point) and `rel_speed_hz` (the device's machine speed
        minus the COI speed seen by its controller, Hz).  Empty without storage."""
        info = {int(d["device"]): d for d in self.meta.get("storage", [])}
        names = {1: "absorb", 0: "idle", -1: "inject"}
        out = []
        for t, dev, mode, rel in self.meta.get("switchings", []):
            d, m = info.get(int(dev), {}), float(mode)
            code = int(m) if m.is_integer() else m
            out.append({"t_s": float(t), "device": int(dev), "bus": d.get("bus"),
                        "machine": d.get("machine"), "mode": names.get(code, f"{m:g}"),
                        "mode_code": code, "rel_speed_hz": float(rel)})
        return out

    # -- export -------------------------------------------------------------------------
    def columns(self) -> tuple[list[str], np.ndarray]:
        """CSV header and data matrix (n_t, n_columns)."""
        names, blocks = ["t"], [self.t[:, None]]
        for s in SERIES:
            names += [f"{SERIES_UNITS[s]}.G{int(k)}" for k in self.machines]
            blocks.append(getattr(self, s))
        names += [f"vmag_pu.B{int(n)}" for n in self.buses]
        names += [f"vang_rad.B{int(n)}" for n in self.buses]
        blocks += [self.vmag, self.vang]
        if self.pesd is not None and self.devices.size:
            names += [f"pesd_pu.D{int(d)}" for d in self.devices]
            blocks.append(self.pesd)
        return names, np.hstack(blocks)

    def to_csv(self, path: str | os.PathLike) -> Path:
        """Write the CSV atomically (temporary file then rename)."""
        names, data = self.columns()
        return atomic_write(path, lambda f: np.savetxt(f, data, delimiter=",", header=",".join(names),
                                                       comments="", fmt="%.10g"))

    def to_npz(self, path: str | os.PathLike) -> Path:
        """Write every array and the verdict to a compressed .npz, atomically."""
        arrays = {k: v for k, v in self.__dict__.items() if isinstance(v, np.ndarray)}
        arrays["verdict"] = np.array([self.stable, self.t_separation or np.nan], float)
        arrays["separated"] = np.asarray(self.separated, int)
        return atomic_write(path, lambda f: np.savez_compressed(f, **arrays), mode="wb")

    @classmethod
    def from_npz(cls, path: str | os.PathLike) -> "SimulationResult":
        """Read a result written by `to_npz`."""
        with np.load(path) as z:
            d = {k: z[k] for k in z.files}
        stable, tsep = d.pop("verdict")
        sep = list(d.pop("separated"))
        return cls(**d, stable=bool(stable), t_separation=None if np.isnan(tsep) else tsep,
                   separated=sep)
