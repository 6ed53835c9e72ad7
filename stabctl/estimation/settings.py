"""The settings of a set of PMUs (`PMUSettings`): reporting rate, accuracy limits read as
k-sigma bounds, latency, losses and the frequency window (IEEE C37.118.1-2011; the noise
model is described in `stabctl.estimation.pmu`).  A module of its own, importing nothing
heavy, so that the command line takes its defaults from here.

Reporting rates (C37.118.1-2011 clause 5.3, Table 1): a PMU reports at one of the rates of
its system's nominal frequency, 10, 12, 15, 20, 30 or 60 frames/s at 60 Hz and 10, 25 or
50 frames/s at 50 Hz, and the clause allows higher rates (120 and 100 frames/s here, as
PMUs offer them).  `PMUSettings` knows no case, so it takes a rate of either list;
`check_rate` checks one against a case's nominal frequency (`rates_at`), and
`nominal_rate` is the default the command line gives a case (one frame per cycle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from stabctl.errors import InputError, number_text

#: reporting rates (frames/s) of each nominal frequency (Hz): C37.118.1-2011 Table 1, and
#: the higher rate clause 5.3 allows, two frames per cycle
RATES_AT: dict[float, tuple[float, ...]] = {
    60.0: (10.0, 12.0, 15.0, 20.0, 30.0, 60.0, 120.0),
    50.0: (10.0, 25.0, 50.0, 100.0),
}
#: every rate of either list: what `PMUSettings` accepts (it does not know the case)
RATES = tuple(sorted({r for rates in RATES_AT.values() for r in rates}))


def _listed(rates) -> str:
    return ", ".join(f"{r:g}" for r in rates)


#: the rates of both lists, as messages name them
RATES_TEXT = " or ".join(f"{_listed(r)} frames/s at {f:g} Hz" for f, r in RATES_AT.items())
#: the least `PMUSettings.k_sigma`: the errors' standard deviations are the C37.118.1
#: limits over k, so k = 1e-12 drew frequencies of -3.9e9 Hz and 1e-320 inf (round 55 AS:
#: non-finite frames, a C37.118.2 encoder's OverflowError); 1e-3 keeps a thousand-sigma
#: stress test of the estimators
K_SIGMA_MIN = 1e-3
#: the shortest `PMUSettings.window_cycles`: a one-cycle DFT, the shortest phasor
#: estimator (the P-class reference filter of C37.118.1 Annex C spans two); 1e-320 cycles
#: made inf and NaN frequencies (round 55 AS)
WINDOW_CYCLES_MIN = 1.0


def rates_at(f0: float) -> tuple[float, ...]:
    """The reporting rates of a system of nominal frequency `f0`.

    Parameters
    ----------
    f0 : float
        Nominal frequency, Hz.

    Returns
    -------
    tuple of float
        Frames/s, ascending: `RATES_AT` of 50 or 60 Hz; at another frequency, for which
        C37.118.1 lists none, every rate of either (`RATES`).
    """
    return RATES_AT.get(float(f0), RATES)


def nominal_rate(f0: float) -> float:
    """The default reporting rate of a system of nominal frequency `f0`: one frame per
    cycle, 60 frames/s at 60 Hz and 50 at 50 Hz (at another frequency the highest rate of
    `rates_at` not above one per cycle, or its lowest).

    Parameters
    ----------
    f0 : float
        Nominal frequency, Hz.

    Returns
    -------
    float
        Frames/s.
    """
    rates = rates_at(f0)
    return max((r for r in rates if r <= f0), default=rates[0])


def check_rate(
    rate: float, f0: float, given: str = "PMUSettings(rate={})", fix: str = "pass {}"
) -> None:
    """Refuse a reporting rate that is not one of a system's (`rates_at`).

    Parameters
    ----------
    rate : float
        Frames/s.
    f0 : float
        The case's nominal frequency, Hz.
    given : str
        How the message names the rate: a format with one ``{}`` for it, e.g.
        ``"--rate {}"``.
    fix : str
        What the message tells to do, a format with one ``{}`` for `given` of the
        nominal rate (`nominal_rate`), e.g. ``"give {}"``.

    Raises
    ------
    InputError
        `rate` not a rate of `f0`, naming the rate, the frequency and its rates, and
        suggesting the nominal-frequency rate.
    """
    rates = rates_at(f0)
    if rate in rates:
        return
    other = [f"{f:g} Hz" for f, r in RATES_AT.items() if rate in r and f != f0]
    also = f"; {number_text(rate)} frames/s is a rate of {' and '.join(other)} systems"
    source = (
        f"C37.118.1-2011 Table 1 reporting rates at {f0:g} Hz, with the higher rate of clause 5.3"
        if float(f0) in RATES_AT
        else "the C37.118.1-2011 rates of 50 and 60 Hz systems"
    )
    raise InputError(
        f"{given.format(number_text(rate))}: must be one of {_listed(rates)} frames/s on "
        f"a {f0:g} Hz system ({source}){also if other else ''}: "
        f"{fix.format(given.format(number_text(nominal_rate(f0))))}"
        + (", one frame per cycle" if nominal_rate(f0) == f0 else "")
    )


@dataclass(frozen=True)
class PMUSettings:
    """Reporting rate, accuracy limits, latency and losses of a set of PMUs.

    Attributes:
        rate: frames per second, one of `RATES` (the rates of 50 and 60 Hz systems; the
            functions that know the case refuse one that is not its frequency's,
            `check_rate`).
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
                f"PMU rate must be one of {RATES_TEXT} (C37.118.1-2011 Table 1 and "
                f"clause 5.3), got {number_text(self.rate)}"
            )
        for name in ("tve", "fe_hz", "rfe_hz_s", "latency_s"):
            if not 0 <= getattr(self, name) < float("inf"):
                raise InputError(
                    f"PMUSettings({name}): PMU accuracy limits and latency must be finite and "
                    f">= 0, got {getattr(self, name)}"
                )
        if not K_SIGMA_MIN <= self.k_sigma < float("inf"):
            raise InputError(
                f"PMUSettings(k_sigma): must be finite and >= {K_SIGMA_MIN:g} (the limits as "
                f"that many standard deviations: below it the drawn errors leave any PMU's "
                f"range), got {self.k_sigma}"
            )
        if not 0 <= self.drop_prob < 1:
            raise InputError(f"dropped-frame probability must be in [0, 1), got {self.drop_prob}")
        if not WINDOW_CYCLES_MIN <= self.window_cycles < float("inf"):
            raise InputError(
                f"PMU estimation window must be >= {WINDOW_CYCLES_MIN:g} cycle (a one-cycle "
                f"DFT, the shortest phasor estimator), got {self.window_cycles}"
            )

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
