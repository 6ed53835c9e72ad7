"""The settings of a set of PMUs (`PMUSettings`): reporting rate, accuracy limits read as
k-sigma bounds, latency, losses and the frequency window (IEEE C37.118.1-2011; the noise
model is described in `stabctl.estimation.pmu`).  A module of its own, importing nothing
heavy, so that the command line takes its defaults from here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from stabctl.errors import InputError, number_text

RATES = (10.0, 12.0, 15.0, 20.0, 30.0, 60.0, 120.0)  # frames/s at 60 Hz (C37.118.1 5.3)


@dataclass(frozen=True)
class PMUSettings:
    """Reporting rate, accuracy limits, latency and losses of a set of PMUs.

    Attributes:
        rate: frames per second (one of `RATES`).
        tve: total vector error limit (fraction, 0.01 = 1 %), C37.118.1 Table 3.
        fe_hz: frequency error limit (Hz), Table 4.
        rfe_hz_s: ROCOF error limit (Hz/s), Table 4.
        k_sigma: the limits are k standard deviations (see the module docstring).
        latency_s: delay from a frame's time stamp to its arrival (s), >= 0.
        drop_prob: probability that a frame never arrives, in [0, 1).
        window_cycles: frequency and ROCOF estimation window (cycles of the nominal
            frequency), > 0; 2 is the P-class filter length of the reference model of
            IEEE C37.118.1-2011 Annex C (kept by IEC/IEEE 60255-118-1:2018); see
            `window_estimates`.
    Raises InputError for values out of range.
    """

    rate: float = 60.0
    tve: float = 0.01
    fe_hz: float = 0.005
    rfe_hz_s: float = 0.01
    k_sigma: float = 3.0
    latency_s: float = 0.05
    drop_prob: float = 0.0
    window_cycles: float = 2.0

    def __post_init__(self):
        if self.rate not in RATES:
            raise InputError(
                f"PMU rate must be one of {', '.join(f'{r:g}' for r in RATES)} "
                f"frames/s, got {number_text(self.rate)}"
            )
        for name in ("tve", "fe_hz", "rfe_hz_s", "latency_s"):
            if not 0 <= getattr(self, name) < float("inf"):
                raise InputError(
                    f"PMUSettings({name}): PMU accuracy limits and latency must be finite and "
                    f">= 0, got {getattr(self, name)}"
                )
        if not 0 < self.k_sigma < float("inf"):
            raise InputError(f"PMUSettings(k_sigma): must be finite and > 0, got {self.k_sigma}")
        if not 0 <= self.drop_prob < 1:
            raise InputError(f"dropped-frame probability must be in [0, 1), got {self.drop_prob}")
        if not 0 < self.window_cycles < float("inf"):
            raise InputError(f"PMU estimation window must be > 0 cycles, got {self.window_cycles}")

    def window_s(self, f0: float) -> float:
        """The frequency estimation window (s) at nominal frequency f0 (Hz)."""
        return self.window_cycles / f0

    @property
    def sigma_phasor(self) -> float:
        """Standard deviation of the real and of the imaginary part of the relative phasor
        error e (so of the relative magnitude error and of the angle error in rad)."""
        return self.tve / (self.k_sigma * math.sqrt(2.0))

    @property
    def sigma_freq(self) -> float:
        """Standard deviation of the frequency error (Hz)."""
        return self.fe_hz / self.k_sigma

    @property
    def sigma_rocof(self) -> float:
        """Standard deviation of the ROCOF error (Hz/s)."""
        return self.rfe_hz_s / self.k_sigma
