"""Ambient load fluctuation: random real-power variations of the loads that drive the
simulator (ambient noise without a fault).

Every bus load with P > 0 in the power flow (`case.buses.pload`) gets a deviation x(t),
relative to its P, from an Ornstein-Uhlenbeck process

    dx = -x / tau dt + sd sqrt(2 / tau) dW,    x(0) = 0,

stationary standard deviation sd, autocorrelation exp(-|s| / tau), the loads independent.
It is sampled exactly at the command instants t_k = k dt (AR(1): x_k = a x_(k-1) +
sd sqrt(1 - a^2) e_k, a = exp(-dt / tau), e_k standard normal from a seeded
`numpy.random.Generator`; `scipy.signal.lfilter` runs the recursion), so the variance at
t_k is sd^2 (1 - a^(2k)), and held between samples.  x(0) = 0 starts from the power
flow: the process is stationary after a few tau.  Reactive power is not varied.

The deviations enter the simulation as externally commanded real-power devices at the
load buses (`stabctl.storage.devices.StorageDevice`, rating = the load's P, set-point = x,
`ExternalCommands`, `Simulator.run_commanded`): the simulator's own network and load
equations, no second model.  A device's power is drawn like a load (+ absorbs), so x > 0
is a load increase.  The voltage gate of the fleet (0 here; the ESDs' 0.8 pu when the
loads share a fleet with ESDs, `closed_loop.run_closed_loop`) applies to them too.

The model's structure, a percent standard deviation of each load and a filter time
constant, is PowerWorld's random load model LDRANDOM (PercStdDev, Tfilter); ambient-data
mode meters assume such random load variations as the excitation (Peric and Vanfretti,
"Power-system ambient-mode estimation considering spectral load properties", IEEE
Trans. Power Syst. 29(3), 2014).  The default values (1 % of each load, tau = 2 s) are
an assumption of this study, not taken from a measurement.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from stabctl.case import Case
from stabctl.dynamics.driver import CommandFrames
from stabctl.dynamics.results import SimulationResult
from stabctl.errors import InputError
from stabctl.storage.control import ExternalCommands
from stabctl.storage.devices import StorageDevice, StorageFleet


@dataclass(frozen=True)
class AmbientLoad:
    """Ambient load fluctuation (module docstring).

    pct: stationary standard deviation of each load's real power (% of its power-flow P);
    tau_s: correlation time (s); seed: noise stream (`numpy.random.SeedSequence`).
    Raises InputError for pct < 0 or tau_s <= 0.
    """

    pct: float = 1.0
    tau_s: float = 2.0
    seed: int = 0

    def __post_init__(self):
        if self.pct < 0 or not self.tau_s > 0:
            raise InputError(
                f"ambient load needs pct >= 0 and tau > 0, got {self.pct}, {self.tau_s}"
            )

    def devices(self, case: Case) -> tuple[StorageDevice, ...]:
        """One commanded device per bus load with P > 0, rated at that P (MW)."""
        p = case.buses.pload * case.base_mva
        return tuple(
            StorageDevice(bus=int(b), machine=None, pmax_mw=float(mw))
            for b, mw in zip(case.buses.number, p)
            if mw > 0
        )

    def deviations(self, n: int, dt: float, n_loads: int) -> np.ndarray:
        """x (n, n_loads) at t_k = k dt, k = 0 .. n-1, relative to each load's P."""
        return ou_samples(n, dt, self.tau_s, self.pct / 100.0, n_loads, self.seed)

    def schedule(self, case: Case, n: int, rate: float):
        """The load devices and their set-points as a function of the command instant
        t = k / rate (k < n): (devices, set_points(t) -> (n_loads,))."""
        devs = self.devices(case)
        x = self.deviations(n, 1.0 / rate, len(devs))
        return devs, lambda t: x[int(round(t * rate))]


def ou_samples(n: int, dt: float, tau: float, sd: float, m: int, seed: int) -> np.ndarray:
    """m independent Ornstein-Uhlenbeck paths (n, m) sampled exactly every dt (s), from
    x = 0 (module docstring): stationary standard deviation sd, correlation time tau (s)."""
    a = np.exp(-dt / tau)
    e = np.random.default_rng(np.random.SeedSequence(seed)).standard_normal((n, m))
    e[0] = 0.0
    return lfilter([sd * np.sqrt(1 - a * a)], [1.0, -a], e, axis=0)


def simulate(
    sim, t_end: float, ambient: AmbientLoad, rate: float = 60.0, events=(), h: float | None = None
) -> SimulationResult:
    """A run of `sim` (a `Simulator`) to t_end (s) with the loads fluctuating, the deviation
    updated `rate` times per second; `events` as `Simulator.run`.  The result's `pesd`
    holds the load deviations (pu, system base), one column per load of
    `ambient.devices(case)`.  Raises as `Simulator.run_commanded`."""
    frames = np.arange(int(np.floor(t_end * rate + 1e-9)) + 1) / rate
    devs, set_points = ambient.schedule(sim.case, frames.size, rate)
    fleet = StorageFleet(devs, ExternalCommands(v_gate_pu=0.0))
    schedule = CommandFrames(
        frames, lambda t, _: set_points(t), history_s=0.0
    )  # the set points read no trajectory
    return sim.run_commanded(events, t_end, fleet, schedule, h=h)
