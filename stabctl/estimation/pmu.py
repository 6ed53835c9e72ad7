"""Phasor measurement units (PMUs): what the ESD controllers see in the field.

A PMU at a bus reports, at a fixed rate, the positive-sequence voltage phasor of the bus, the
current phasor of one generator or storage device there (P and Q follow from the two),
the frequency and the rate of change of frequency (ROCOF), each with a time stamp
(IEEE C37.118.1-2011, clause 4: synchrophasor, frequency and ROCOF definitions).  The frames
reach the controller late (communication latency) and some never arrive (dropped).

True values come from a `SimulationResult`, on its step grid, then linearly interpolated to
the reporting instants (magnitude and unwrapped angle separately):

- voltage: `vmag`, `vang` of the bus (angles in the synchronous frame, as C37.118's
  synchrophasor against a nominal-frequency reference, clause 4.2);
- current of a generator at its terminal bus: the sum of the currents injected into the
  branches at that bus (Kirchhoff at the terminal bus, which carries no load in the PSTess
  cases); checked against the simulated electrical power, `P = Re(V conj(I))` (but at
  the last point, see `phasor_truth`); at another
  bus (normally its high-voltage bus): the current flowing into that bus through the
  branches from the terminal bus; of a storage device: `-P_esd / conj(V)` (the device
  draws real power only; generator sign convention: current into the network);
- frequency and ROCOF: over the PMU's estimation window W (`PMUSettings.window_cycles`
  cycles of f0, two by default, the P-class filter length of the C37.118.1-2011 Annex C
  reference model), from the unwrapped bus voltage angle theta, linear between grid points
  (`window_estimates`): f = f0 + (theta(c + W/2) - theta(c - W/2)) / (2 pi W) over the
  window centred at c, ROCOF = the change of f between the windows centred at c -+ W/2,
  over W.  The offline model centres the windows on the frame's time stamp (C37.118.1-2011
  clause 4 and Annex C: a measurement is time-tagged at the centre of its window), moved
  inside the run near its ends; the in-loop model (`closed_loop`) takes the last complete
  windows before the time stamp (causal).  A network event makes theta jump by d; the
  frequency then errs by d / (2 pi W) for the frames whose window holds the jump, whatever
  the integration step, as a real PMU's does (C37.118.1 excludes such intervals from its
  compliance limits).

Noise (`PMUSettings`): the accuracy limits of C37.118.1-2011 clause 5.5 (steady-state
Table 3: total vector error TVE <= 1 %; Table 4: frequency error FE <= 0.005 Hz, ROCOF
error RFE <= 0.01 Hz/s), or the user's values, are read as k-sigma bounds (k = 3 by
default).  A phasor X is reported as X (1 + e), e complex, circular Gaussian with
independent real and imaginary parts of standard deviation s = TVE / (k sqrt 2): to first
order the magnitude has relative error Re(e) and the angle error Im(e) rad, both of standard
deviation s (k = 3: s = 0.236 %, 2.36 mrad), and TVE = |e| is Rayleigh distributed with
RMS value TVE_limit / k, so P(TVE > limit) = exp(-k^2) (1.2e-4 for k = 3).  Frequency
and ROCOF get independent Gaussian errors of standard deviation FE / k and RFE / k.
Errors are white: independent between frames, channels and PMUs (a compliance-limit
worst case for the noise level; real PMU errors are smaller and correlated in time).

Reporting rates: C37.118.1 clause 5.3 (Table 1) lists 10, 12, 15, 20, 30 and 60 frames/s for
60 Hz systems and 10, 25 and 50 for 50 Hz systems, and allows higher rates (120 and 100
here); `measure` takes only a rate of the truth's nominal frequency
(`stabctl.estimation.settings.check_rate`).  Frame k is
stamped t_k = k / rate; it arrives at t_k + latency, or never with probability `drop_prob`
(independent per frame and PMU).  Every PMU draws from its own random stream
(`numpy.random.SeedSequence(seed).spawn`), so a stream is reproducible from its seed and
adding PMUs at the end does not change the noise of the others.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from stabctl.case import Case
from stabctl.dynamics.results import SimulationResult
from stabctl.errors import InputError
from stabctl.estimation.settings import PMUSettings, check_rate
from stabctl.network.ybus import branch_admittances
from stabctl.storage.devices import hv_bus

KCL_TOLERANCE_PU = 1e-6


@dataclass(frozen=True)
class PMU:
    """One PMU: the bus whose voltage it reports and whose current it reports.

    bus: bus number; machine: number of the generator whose current is measured (at its
    terminal bus or at a bus joined to it by a branch); device: number of the storage
    device (as in `SimulationResult.devices`) whose current is measured instead; neither:
    voltage, frequency and ROCOF only.
    """

    bus: int
    machine: int | None = None
    device: int | None = None

    def __post_init__(self):
        if self.machine is not None and self.device is not None:
            raise InputError(f"PMU at bus {self.bus}: measure a machine or a device, not both")

    @property
    def label(self) -> str:
        what = (
            f"G{self.machine}"
            if self.machine is not None
            else f"D{self.device}"
            if self.device is not None
            else "V"
        )
        return f"B{self.bus}:{what}"


@dataclass(frozen=True)
class PhasorTruth:
    """Noise-free PMU quantities on a time grid: t (n_t,) s; v, i (n_t, n_pmu) complex pu
    (system base; i is NaN for a PMU without current channel); freq (Hz), rocof (Hz/s)
    (n_t, n_pmu); f0 nominal frequency (Hz); window: None if freq and rocof are given on
    the grid (they are interpolated between grid points), else the PMU estimation window
    (s) they are measured over from the angle of v (`angle_truth`; `at` evaluates them at
    any instant)."""

    t: np.ndarray
    pmus: tuple
    v: np.ndarray
    i: np.ndarray
    freq: np.ndarray
    rocof: np.ndarray
    f0: float
    window: float | None = None

    def at(self, t: np.ndarray) -> PhasorTruth:
        """The same quantities at times t (k,) within the grid (window None in the result):
        phasors linearly interpolated (magnitudes and unwrapped angles separately);
        frequency and ROCOF interpolated, or with a window the PMU's estimates at t
        (`centred_estimates`)."""
        t = np.asarray(t, float)
        if self.window is None:
            freq = interp_columns(t, self.t, self.freq)
            rocof = interp_columns(t, self.t, self.rocof)
        else:
            freq, rocof = centred_estimates(self.t, np.angle(self.v), t, self.window, self.f0)
        return PhasorTruth(
            t=t,
            pmus=self.pmus,
            v=_interp_phasor(t, self.t, self.v),
            i=_interp_phasor(t, self.t, self.i),
            freq=freq,
            rocof=rocof,
            f0=self.f0,
        )


class Frame(NamedTuple):
    """One reporting instant of every PMU: t time stamp (s); valid (n_pmu,) bool (False:
    the frame was dropped, its values are NaN); v, i complex pu; freq Hz; rocof Hz/s."""

    t: float
    valid: np.ndarray
    v: np.ndarray
    i: np.ndarray
    freq: np.ndarray
    rocof: np.ndarray

    def of(self, cols) -> Frame:
        """The frame of the PMUs at indices cols only (a sequence of int)."""
        cols = list(cols)
        return Frame(self.t, *(x[cols] for x in self[1:]))


@dataclass(frozen=True)
class Frames(Sequence):
    """Frames held column by column: a sequence of `Frame` (indexing makes each from
    its rows, views of the arrays), at about 50 bytes per PMU and frame where a list of
    Frame objects takes about 200 (a recording of millions of frames is tracked from
    these, `stabctl.estimation.sources.merge`).

    Attributes
    ----------
    t : numpy.ndarray, shape (n_f,)
        Time stamps, s.
    valid : numpy.ndarray, shape (n_f, n_pmu), bool
    v, i : numpy.ndarray, shape (n_f, n_pmu), complex
        Phasors, pu (NaN where invalid).
    freq, rocof : numpy.ndarray, shape (n_f, n_pmu)
        Hz and Hz/s (NaN where invalid).
    """

    t: np.ndarray
    valid: np.ndarray
    v: np.ndarray
    i: np.ndarray
    freq: np.ndarray
    rocof: np.ndarray

    @classmethod
    def missing(cls, n_f: int, n_pmu: int) -> Frames:
        """n_f frames of n_pmu PMUs, every value missing (NaN, invalid), t zero."""
        nan = np.full((n_f, n_pmu), np.nan)
        return cls(np.zeros(n_f), np.zeros((n_f, n_pmu), bool), nan + 0j, nan + 0j, nan, nan.copy())

    def __len__(self) -> int:
        return self.t.size

    def __getitem__(self, k):
        if isinstance(k, slice):
            return Frames(*(x[k] for x in self.columns()))
        return Frame(
            float(self.t[k]), self.valid[k], self.v[k], self.i[k], self.freq[k], self.rocof[k]
        )

    def columns(self) -> tuple:
        """(t, valid, v, i, freq, rocof): the arrays, in `Frame`'s order."""
        return (self.t, self.valid, self.v, self.i, self.freq, self.rocof)


@dataclass(frozen=True)
class FrameStream:
    """The measured frames of a set of PMUs, in time-stamp order.

    Attributes:
        pmus: the PMUs (labels: `labels`); settings: their `PMUSettings`; seed: entropy of
        the random streams; t (n_f,) time stamps (s); arrival (n_f, n_pmu) arrival times
        (s, inf for dropped frames); valid (n_f, n_pmu) bool; v, i (n_f, n_pmu) measured
        phasors (complex pu, NaN where dropped or no current channel); freq (Hz), rocof
        (Hz/s) (n_f, n_pmu); true: the noise-free values at the time stamps.
    """

    pmus: tuple
    settings: PMUSettings
    seed: int
    t: np.ndarray
    arrival: np.ndarray
    valid: np.ndarray
    v: np.ndarray
    i: np.ndarray
    freq: np.ndarray
    rocof: np.ndarray
    true: PhasorTruth

    @property
    def labels(self) -> list[str]:
        return [p.label for p in self.pmus]

    @property
    def power(self) -> np.ndarray:
        """Measured complex power S = V conj(I) (pu system base, generator convention),
        (n_f, n_pmu); P = S.real, Q = S.imag."""
        return self.v * np.conj(self.i)

    def __len__(self) -> int:
        return self.t.size

    def frame(self, k: int) -> Frame:
        """Frame k (all PMUs at time stamp t[k])."""
        return Frame(
            float(self.t[k]), self.valid[k], self.v[k], self.i[k], self.freq[k], self.rocof[k]
        )

    def __iter__(self):
        return (self.frame(k) for k in range(self.t.size))


# -- true quantities from a simulation --------------------------------------------------
def machine_pmus(case: Case, at: str = "terminal") -> tuple:
    """One PMU per generator measuring its current: at its terminal bus (at="terminal") or
    its high-voltage bus (at="hv", `stabctl.storage.devices.hv_bus`). Raises InputError
    otherwise."""
    if at not in ("terminal", "hv"):
        raise InputError(f"PMU placement must be 'terminal' or 'hv', got {at!r}")
    nums = [int(n) for n in case.machines.number]
    buses = (
        [int(b) for b in case.machines.bus] if at == "terminal" else [hv_bus(case, n) for n in nums]
    )
    return tuple(PMU(bus=b, machine=n) for b, n in zip(buses, nums))


def window_estimates(
    t: np.ndarray, ang: np.ndarray, f_at, rocof_at, window: float, f0: float
) -> tuple[np.ndarray, np.ndarray]:
    """A PMU's frequency (Hz) and ROCOF (Hz/s) over its estimation window, from bus angles.

    The phase advance over the window (IEEE C37.118.1-2011 clause 4.3, frequency as the
    derivative of the phase, taken over the estimation window of the Annex C reference
    model, two cycles for P class):

        f(c) = f0 + (theta(c + W/2) - theta(c - W/2)) / (2 pi W)
        ROCOF(r) = (f(r + W/2) - f(r - W/2)) / W
                 = (theta(r + W) - 2 theta(r) + theta(r - W)) / (2 pi W^2)

    with theta the unwrapped angle, linear between grid points and held at its first and
    last values outside the grid (a run starts from steady state).  A jump d of theta
    inside a window adds d / (2 pi W) to f, independent of the grid.

    t (n_t,) strictly increasing s; ang (n_t, n) rad, wrapped or not; f_at (k,) centres of
    the frequency windows, rocof_at (k,) centres of the ROCOF window pairs (s); window W s.
    Returns f, rocof (k, n).  Raises InputError for an empty or non-increasing grid or a
    window not > 0.
    """
    if t.size < 1 or np.any(np.diff(t) <= 0):
        raise InputError("PMU frequency needs a strictly increasing time grid")
    if not 0 < window < np.inf:
        raise InputError(f"PMU estimation window must be > 0 s, got {window}")
    f_at = np.atleast_1d(np.asarray(f_at, float))
    rocof_at = np.atleast_1d(np.asarray(rocof_at, float))
    k, half = f_at.size, window / 2
    x = np.concatenate((f_at - half, f_at + half, rocof_at - window, rocof_at, rocof_at + window))
    th = interp_columns(x, t, np.unwrap(ang, axis=0))
    f = f0 + (th[k : 2 * k] - th[:k]) / (2 * np.pi * window)
    r = th[2 * k :].reshape(3, rocof_at.size, -1)
    return f, (r[2] - 2 * r[1] + r[0]) / (2 * np.pi * window**2)


def centred_estimates(
    t: np.ndarray, ang: np.ndarray, at, window: float, f0: float
) -> tuple[np.ndarray, np.ndarray]:
    """`window_estimates` time-tagged at the window centres `at` (k,) s (C37.118.1-2011
    Annex C), the windows moved inside the grid [t0, t_end] near its ends (one-sided
    there; a grid shorter than two windows holds its end values).  Returns f, rocof
    (k, n); raises as `window_estimates`."""
    at = np.asarray(at, float)
    inside = lambda w: np.minimum(np.maximum(at, t[0] + w), t[-1] - w)  # noqa: E731
    return window_estimates(t, ang, inside(window / 2), inside(window), window, f0)


def angle_truth(
    t: np.ndarray, pmus, v: np.ndarray, i: np.ndarray, f0: float, window: float
) -> PhasorTruth:
    """The `PhasorTruth` of phasors v, i (n_t, n_pmu) on grid t (n_t,) s, its frequency and
    ROCOF the PMU's over `window` s from the angle of v (`centred_estimates`).  Raises as
    `window_estimates`."""
    freq, rocof = centred_estimates(t, np.angle(v), t, window, f0)
    return PhasorTruth(
        t=t, pmus=tuple(pmus), v=v, i=i, freq=freq, rocof=rocof, f0=f0, window=window
    )


def phasor_truth(
    case: Case, result: SimulationResult, pmus, window_cycles: float = PMUSettings.window_cycles
) -> PhasorTruth:
    """True PMU quantities of `pmus` on the result's step grid (see the module docstring),
    frequency and ROCOF over a window of window_cycles cycles (`angle_truth`; measure it
    with `PMUSettings` of the same window).

    A repeated time point (a zero-length interval at an event) keeps its last value.  The
    check of generator currents against pelect leaves out the run's last point, whose
    pelect and voltages the simulator may take from different evaluations (storage
    switching in the last step).  A PMU at a machine's terminal measures the machine's own
    current, conj((pelect + j qelect) / V) (a load or shunt at the bus is not in it); one at
    its HV bus the step-up branch's.  Raises UnknownBusError / CaseError for unknown buses
    or machines, InputError for a device not in the result or not at the PMU's bus, a PMU
    at an HV bus whose step-up is not the machine's only connection (a load, shunt,
    machine or other branch at the terminal bus), or (a result without qelect) a
    generator current that cannot be reconstructed (P from the phasors differs from the
    simulated pelect by more than 1e-6 pu: load at the terminal bus, or a branch there
    tripped or faulted).
    """
    keep = np.r_[np.diff(result.t) > 0, True]
    t = result.t[keep]
    V = (result.vmag * np.exp(1j * result.vang))[keep]
    cols = case.bus_indices([p.bus for p in pmus])
    cur = np.stack([_current(case, result, p, V, keep) for p in pmus], axis=1)
    return angle_truth(t, pmus, V[:, cols], cur, case.freq_hz, window_cycles / case.freq_hz)


def _current(case: Case, result: SimulationResult, pmu: PMU, V: np.ndarray, keep) -> np.ndarray:
    """True current phasor (n_t,) of the PMU's current channel (NaN if none)."""
    n = V.shape[0]
    b = case.bus_index(pmu.bus)
    if pmu.device is not None:
        return _device_current(result, pmu, V[:, b], keep)
    if pmu.machine is None:
        return np.full(n, np.nan + 0j)
    k = case.machine_index(pmu.machine)
    term = case.bus_index(int(case.machines.bus[k]))
    if b == term and result.qelect is not None:  # the machine's own: S = V conj(I)
        return np.conj((result.pelect + 1j * result.qelect)[keep, k] / V[:, term])
    ba = branch_admittances(case)
    if b == term:  # Kirchhoff at the terminal bus: everything leaving it into the network
        cur = V[:, term] * (case.buses.gshunt[term] + 1j * case.buses.bshunt[term])
        for j in np.flatnonzero(ba.f == term):
            cur = cur + ba.yff[j] * V[:, term] + ba.yft[j] * V[:, ba.t[j]]
        for j in np.flatnonzero(ba.t == term):
            cur = cur + ba.ytf[j] * V[:, ba.f[j]] + ba.ytt[j] * V[:, term]
        # the last point is left out: with storage switching in the last step the simulator
        # records its pelect and bus voltages from different evaluations
        p_err = np.abs((V[:, term] * np.conj(cur)).real - result.pelect[keep, k])[:-1].max()
        if p_err > KCL_TOLERANCE_PU:
            raise InputError(
                f"PMU at bus {pmu.bus}: the current of machine {pmu.machine} "
                f"is not the sum of its terminal branch currents (P differs "
                f"from pelect by {p_err:.2e} pu: load, fault or trip at the bus)"
            )
        return cur
    rows = np.flatnonzero(((ba.f == term) & (ba.t == b)) | ((ba.f == b) & (ba.t == term)))
    if rows.size == 0:
        raise InputError(
            f"PMU at bus {pmu.bus}: no branch joins it to the terminal bus "
            f"{int(case.machines.bus[k])} of machine {pmu.machine}"
        )
    _check_step_up(case, pmu, term, b, ba)
    cur = np.zeros(n, complex)
    for j in rows:  # current into bus b = minus the current injected into the branch at b
        cur -= (
            (ba.ytf[j] * V[:, term] + ba.ytt[j] * V[:, b])
            if ba.t[j] == b
            else (ba.yff[j] * V[:, b] + ba.yft[j] * V[:, term])
        )
    return cur


def _check_step_up(case: Case, pmu: PMU, term: int, b: int, ba) -> None:
    """InputError unless the machine's current all flows from its terminal bus (row term)
    to the PMU's bus (row b): a load, a shunt, another machine or another branch at the
    terminal bus takes part of it, and the current the PMU measures is not the machine's
    (the estimators would read the rotor from it through the step-up's impedance)."""
    other = {int(x) for x in np.r_[ba.t[ba.f == term], ba.f[ba.t == term]]} - {b}
    k = case.machine_index(pmu.machine)
    what = [
        name
        for name, there in (
            ("load", case.buses.pload[term] != 0 or case.buses.qload[term] != 0),
            ("shunt", case.buses.gshunt[term] != 0 or case.buses.bshunt[term] != 0),
            ("another machine", np.count_nonzero(case.machines.bus == case.machines.bus[k]) > 1),
            (
                f"branches to bus(es) {sorted(int(case.buses.number[x]) for x in other)}",
                bool(other),
            ),
        )
        if there
    ]
    if what:
        raise InputError(
            f"PMU at bus {pmu.bus}: the terminal bus {int(case.machines.bus[k])} of "
            f"{case.machine_name(pmu.machine)} also has {' and '.join(what)}, so the current "
            f"from it to bus {pmu.bus} is not the machine's; put the PMU at the terminal "
            "(--pmu-at terminal), which measures the machine's own current"
        )


def _device_current(result: SimulationResult, pmu: PMU, v: np.ndarray, keep) -> np.ndarray:
    """Current injected by a storage device (it draws real power P_esd only)."""
    info = {d["device"]: d for d in result.meta.get("storage", [])}
    if pmu.device not in info:
        raise InputError(f"PMU at bus {pmu.bus}: storage device {pmu.device} is not in the result")
    if info[pmu.device]["bus"] != pmu.bus:
        raise InputError(
            f"PMU at bus {pmu.bus}: storage device {pmu.device} is at bus {info[pmu.device]['bus']}"
        )
    col = int(np.flatnonzero(result.devices == pmu.device)[0])
    return -result.pesd[keep, col] / np.conj(v)  # type: ignore[index]  # storage: has pesd


# -- measurement ------------------------------------------------------------------------
def frame_times(t_end: float, rate: float) -> np.ndarray:
    """Reporting instants k / rate in [0, t_end] (s); the integer arithmetic keeps
    multiples of 1/60 s exact, so events at whole cycles fall on frames."""
    return np.arange(int(np.floor(t_end * rate + 1e-9)) + 1) / rate


def measure(
    truth: PhasorTruth, settings: PMUSettings = PMUSettings(), seed: int = 0
) -> FrameStream:
    """The frame stream of the PMUs of `truth`: true values at the reporting instants
    within the truth's time span, plus noise, latency and dropped frames (module docstring).

    seed: non-negative integer; the same seed gives the same stream.  Raises InputError
    for a negative seed, a rate that is not one of the truth's nominal frequency
    (`check_rate`: the default 60 frames/s on a 50 Hz case too, pass
    ``PMUSettings(rate=50)``), a truth shorter than one frame interval, or a truth whose
    frequency window (`PhasorTruth.window`) is not the settings' `window_cycles`.
    """
    if seed < 0:
        raise InputError(f"seed must be >= 0, got {seed}")
    check_rate(settings.rate, truth.f0)
    if truth.window is not None and not np.isclose(
        truth.window, settings.window_s(truth.f0), rtol=1e-12, atol=0.0
    ):
        raise InputError(
            f"the truth's frequency window is {truth.window * truth.f0:g} cycles, "
            f"the PMU settings' {settings.window_cycles:g}"
        )
    t = truth.t[0] + frame_times(truth.t[-1] - truth.t[0], settings.rate)
    if t.size < 2:
        raise InputError("the run is shorter than one PMU frame interval")
    true = truth.at(t)
    n_f, n_p = true.v.shape
    noise = [
        _pmu_noise(np.random.default_rng(s), n_f, settings)
        for s in np.random.SeedSequence(seed).spawn(n_p)
    ]
    ev, ei, ef, er, drop = (np.stack(a, axis=1) for a in zip(*noise))
    valid = ~drop
    nan = np.where(valid, 1.0, np.nan)
    v, i = true.v * (1 + ev) * nan, true.i * (1 + ei) * nan
    freq, rocof = (true.freq + ef) * nan, (true.rocof + er) * nan
    return _stream(truth.pmus, settings, seed, t, valid, v, i, freq, rocof, true)


#: a received stream whose frequency is further from the run's, RMS, than this many of its
#: PMUs' stated standard deviations (`PMUSettings.sigma_freq`) does not measure that run
NOT_THIS_RUN_SIGMAS = 10.0


def stream_of_frames(
    frames, truth: PhasorTruth, settings: PMUSettings, seed: int = 0
) -> FrameStream:
    """The `FrameStream` of frames received rather than drawn here (a recording, a
    C37.118.2 stream over TCP: `stabctl.estimation.sources`), against the truth of the run
    they measure.

    Parameters
    ----------
    frames : sequence of Frame
        In time-stamp order, one column per PMU of `truth` (its order).
    truth : PhasorTruth
        The noise-free quantities of the run the frames measure; its values at the frames'
        time stamps become the stream's ``true``.
    settings : PMUSettings
        The PMUs' settings (rate, noise limits, latency) the estimators are tuned to.
    seed : int, optional
        The seed the frames were drawn with, as the stream's label (0).

    Returns
    -------
    FrameStream
        Arrival at time stamp + ``settings.latency_s`` for the frames of each PMU that
        came (valid), inf for the others.

    Raises
    ------
    InputError
        No frame, frames of another number of PMUs, time stamps out of order or outside
        the truth's span (more than a microsecond, the C37.118.2 time base), or frames
        whose frequency is further from the truth than `NOT_THIS_RUN_SIGMAS` (RMS).
    """
    frames = list(frames)
    if not frames:
        raise InputError("no PMU frame received")
    n = len(truth.pmus)
    if any(f.valid.size != n for f in frames):
        raise InputError(f"frames of {frames[0].valid.size} PMUs for a run with {n}")
    t = np.array([f.t for f in frames])
    if np.any(np.diff(t) <= 0):
        raise InputError(f"frame time stamps out of order at frame {int(np.argmin(np.diff(t)))}")
    if t[0] < truth.t[0] - 1e-6 or t[-1] > truth.t[-1] + 1e-6:
        raise InputError(
            f"frames from {t[0]:g} s to {t[-1]:g} s, the run from {truth.t[0]:g} s to "
            f"{truth.t[-1]:g} s: not a stream of this run"
        )
    valid = np.array([f.valid for f in frames], bool)
    v, i, freq, rocof = (np.array([getattr(f, x) for f in frames]) for x in Frame._fields[2:])
    true = truth.at(np.clip(t, truth.t[0], truth.t[-1]))
    err = (freq - true.freq)[valid]
    rms = float(np.sqrt(np.mean(err**2))) if err.size else 0.0
    if rms > NOT_THIS_RUN_SIGMAS * settings.sigma_freq:
        raise InputError(
            f"the frames do not measure this run: their frequency is {1e3 * rms:.1f} mHz RMS "
            f"from the simulated one, more than {NOT_THIS_RUN_SIGMAS:g} times the PMUs' "
            f"stated {1e3 * settings.sigma_freq:.2f} mHz (another case, fault or clearing?)"
        )
    return _stream(truth.pmus, settings, seed, t, valid, v, i, freq, rocof, true)


def _stream(pmus, settings, seed, t, valid, v, i, freq, rocof, true) -> FrameStream:
    """The FrameStream of these frames, each valid one arriving latency_s after its time
    stamp (the others never: inf)."""
    return FrameStream(
        pmus=pmus,
        settings=settings,
        seed=seed,
        t=t,
        arrival=np.where(valid, t[:, None] + settings.latency_s, np.inf),
        valid=valid,
        v=v,
        i=i,
        freq=freq,
        rocof=rocof,
        true=true,
    )


def _pmu_noise(rng: np.random.Generator, n: int, s: PMUSettings):
    """One PMU's errors for n frames, drawn in a fixed order: relative voltage and current
    phasor errors (complex), frequency (Hz) and ROCOF (Hz/s) errors, dropped mask."""
    ev = rng.normal(0.0, s.sigma_phasor, (n, 2)) @ np.array([1.0, 1j])
    ei = rng.normal(0.0, s.sigma_phasor, (n, 2)) @ np.array([1.0, 1j])
    ef = rng.normal(0.0, s.sigma_freq, n)
    er = rng.normal(0.0, s.sigma_rocof, n)
    drop = rng.random(n) < s.drop_prob
    return ev, ei, ef, er, drop


def interp_columns(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """`numpy.interp` of every column of fp (n, m) at x (k,) -> (k, m), in one pass: the
    same formula (fp[j] + slope (x - xp[j]), held at the end values outside xp); xp (n,)
    strictly increasing."""
    if xp.size == 1:
        return np.repeat(fp[:1], x.size, axis=0)
    j = np.clip(np.searchsorted(xp, x, side="right") - 1, 0, xp.size - 2)
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])[:, None]
    out = slope * (x - xp[j])[:, None] + fp[j]
    out[x <= xp[0]] = fp[0]
    out[x >= xp[-1]] = fp[-1]
    return out


def _interp_phasor(t, tp, z):
    """Interpolate complex columns by magnitude and unwrapped angle (NaN columns stay)."""
    mag = interp_columns(t, tp, np.abs(z))
    ang = interp_columns(t, tp, np.unwrap(np.nan_to_num(np.angle(z)), axis=0))
    return np.where(np.isnan(mag), np.nan + 0j, mag * np.exp(1j * ang))
