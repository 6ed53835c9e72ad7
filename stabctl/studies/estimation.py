"""Offline evaluation of the speed estimators against the simulated truth.

A disturbance is simulated once (with storage acting on the true speeds if asked), then for
each Monte-Carlo run a PMU frame stream is drawn (`stabctl.estimation.pmu.measure`, run r with seed
S + r) and fed frame by frame to every estimator:

- ``raw``: the PMU frequency taken for the speed (the last valid frame held when one is
  dropped; variance (FE / k)^2);
- ``kf``: `stabctl.estimation.filters.FrequencyKF` (baseline);
- ``ekf``: `stabctl.estimation.filters.SwingEKF` (model-based).

Errors against the true rotor speeds (mHz, 1 pu speed = f0 Hz) over a window (the
post-fault swing: from the last network event to the end): RMSE of the machine speeds, of
the COI speed (paper eq. 40) and of the relative speeds omega_i - omega_COI the ESD
controllers use, each at the frame time stamps; the relative-speed RMSE a controller sees
at the arrival of each frame (latency included), with the estimate as delivered and
forecast to the arrival instant (`forecast`); the fraction of NIS values inside the
two-sided 95 % chi-square interval.  False ESD actions: the paper's Table 3 rule
(`stabctl.storage.devices.desired_mode`: absorb above +deadband, inject below -deadband) applied to
each estimate of the relative speed on runs without fault (with ambient load fluctuation,
`stabctl.estimation.ambient`); every switching from idle to a running mode is a false action.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from stabctl._jit.decorators import njit
from stabctl.case import Case
from stabctl.dynamics.results import SimulationResult
from stabctl.errors import InputError
from stabctl.estimation.filters import FrequencyKF, SwingEKF, nis_bounds
from stabctl.estimation.models import (
    FrequencyTuning,
    MachineModels,
    SwingTuning,
    machine_models,
    relative_speeds,
)
from stabctl.estimation.pmu import (
    FrameStream,
    machine_pmus,
    measure,
    phasor_truth,
    stream_of_frames,
)
from stabctl.estimation.settings import PMUSettings
from stabctl.storage import control as law
from stabctl.storage import devices as st

ESTIMATORS = ("raw", "kf", "ekf")
METRICS = (
    "speed_rmse_mhz",
    "coi_rmse_mhz",
    "rel_rmse_mhz",
    "rel_max_mhz",
    "rel_arrival_rmse_mhz",
    "rel_forecast_rmse_mhz",
    "nis_inside",
)


@dataclass(frozen=True)
class Track:
    """One estimator's output over a stream: speed, var (n_f, n_mac) pu, pu^2 at the frame
    time stamps; ahead, ahead_var: the same forecast to each frame's arrival; nis
    (n_f, n_mac), NaN where no update; dof of the NIS."""

    speed: np.ndarray
    var: np.ndarray
    ahead: np.ndarray
    ahead_var: np.ndarray
    nis: np.ndarray
    dof: int


def run_estimators(
    stream: FrameStream,
    models: MachineModels,
    kf_tuning: FrequencyTuning = FrequencyTuning(),
    ekf_tuning: SwingTuning = SwingTuning(),
) -> dict[str, Track]:
    """Tracks of the raw PMU frequency and of both filters fed every frame in order."""
    filters = {
        "kf": FrequencyKF(models.pmu, stream.settings, kf_tuning, models.f0),
        "ekf": SwingEKF(models, stream.settings, ekf_tuning),
    }
    out = {"raw": _raw_track(stream, models)}
    lat = stream.settings.latency_s
    for name, f in filters.items():
        rows = []
        for fr in stream:
            s, v = f.step(fr)
            rows.append((s, v, *f.forecast(lat), f.nis.copy()))
        out[name] = Track(*(np.array(a) for a in zip(*rows)), dof=f.dof)  # type: ignore[misc, arg-type]
    return out


def _raw_track(stream: FrameStream, models: MachineModels) -> Track:
    """The PMU frequency of each machine's PMU as its speed, dropped frames held."""
    f = stream.freq[:, models.pmu]
    idx = np.where(np.isfinite(f), np.arange(len(stream))[:, None], 0)
    speed = np.take_along_axis(f, np.maximum.accumulate(idx, axis=0), axis=0) / models.f0
    var = np.full_like(speed, (stream.settings.sigma_freq / models.f0) ** 2)
    return Track(speed, var, speed, var, np.full_like(speed, np.nan), dof=0)


#: time stamps this close to a window's end count inside it (s): a stamp k / rate and an
#: end computed as clearing + settling differ by float round-off (1.1 + 0.1 s against
#: the frame 72 / 60 s) and must not move a frame in or out of the window
WINDOW_SLACK_S = 1e-9


def in_window(t: np.ndarray, window: tuple[float, float]) -> np.ndarray:
    """Which time stamps lie in a window, its ends included.

    Parameters
    ----------
    t : numpy.ndarray
        Time stamps, s, shape (n,).
    window : (float, float)
        (start, end), s.

    Returns
    -------
    numpy.ndarray
        Boolean mask, shape (n,): ``start - WINDOW_SLACK_S <= t <= end + WINDOW_SLACK_S``,
        so a stamp on a window end is inside however the end was computed.
    """
    return (t >= window[0] - WINDOW_SLACK_S) & (t <= window[1] + WINDOW_SLACK_S)


def errors(
    track: Track,
    result: SimulationResult,
    stream: FrameStream,
    window: tuple[float, float],
    coi: str = "system",
) -> dict:
    """Error figures of one track (module docstring), mHz; nis_inside NaN for a track
    without NIS.  window: (start, end) s of the time stamps evaluated."""
    f0 = stream.true.f0
    sel = in_window(stream.t, window)
    if not sel.any():
        raise InputError(f"no PMU frame in the window {window} s")
    M = result.inertia
    true = result.speed_at(stream.t[sel])
    late = result.speed_at(stream.t[sel] + stream.settings.latency_s)
    rel = lambda s: relative_speeds(s, s, M, coi)[0]  # noqa: E731
    rms = lambda e: _finite(e, lambda v: np.sqrt(np.mean(v**2))) * f0 * 1e3  # noqa: E731
    e_rel = rel(track.speed[sel]) - rel(true)
    out = {
        "speed_rmse_mhz": rms(track.speed[sel] - true),
        "coi_rmse_mhz": rms((track.speed[sel] - true) @ M / M.sum()),
        "rel_rmse_mhz": rms(e_rel),
        "rel_max_mhz": _finite(e_rel, lambda v: np.max(np.abs(v))) * f0 * 1e3,
        "rel_arrival_rmse_mhz": rms(rel(track.speed[sel]) - rel(late)),
        "rel_forecast_rmse_mhz": rms(rel(track.ahead[sel]) - rel(late)),
    }
    nis = track.nis[sel]
    nis = nis[np.isfinite(nis)]
    if track.dof and nis.size:
        lo, hi = nis_bounds(track.dof)
        out["nis_inside"] = float(np.mean((nis > lo) & (nis < hi)))
    else:
        out["nis_inside"] = float("nan")
    return out


def _finite(values, stat) -> float:
    """``stat`` of the finite entries of ``values``; NaN when there are none (every frame
    lost: a COI or relative error needs a frame of every PMU at once)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return float(stat(v)) if v.size else float("nan")


def monte_carlo(
    case: Case,
    result: SimulationResult,
    settings: PMUSettings,
    runs: int,
    seed: int,
    window: tuple[float, float],
    at: str = "terminal",
    coi: str = "system",
    done: Callable[[], object] | None = None,
) -> dict:
    """Errors of every estimator over `runs` PMU streams (seeds seed .. seed + runs - 1);
    ``done()`` is called after each run's (a progress bar's ``update``), if given.

    Returns {estimator: {metric: {"mean", "std", "min", "max", "runs": [...]}}} ("std"
    None from fewer than two runs: no spread).  Raises InputError for runs < 1.
    """
    if runs < 1:
        raise InputError(f"need at least one Monte-Carlo run, got {runs}")
    pmus = machine_pmus(case, at)
    truth = phasor_truth(case, result, pmus, settings.window_cycles)
    streams = (measure(truth, settings, seed + r) for r in range(runs))
    return _stream_figures(case, result, pmus, streams, window, coi, done)


def received_errors(
    case: Case,
    result: SimulationResult,
    settings: PMUSettings,
    frames,
    seed: int,
    window: tuple[float, float],
    at: str = "terminal",
    coi: str = "system",
) -> dict:
    """Errors of every estimator on frames received rather than drawn (a recording, a
    C37.118.2 stream: `stabctl.estimation.sources`), as `monte_carlo` gives them for one
    run.

    Parameters
    ----------
    case, result : Case, SimulationResult
        The run the frames measure (the truth).
    settings : PMUSettings
        The PMUs' settings the estimators are tuned to.
    frames : sequence of Frame
        The frames, one column per machine PMU (`machine_pmus(case, at)`).
    seed : int
        The seed the frames were drawn with (a label).
    window : (float, float)
        Time stamps evaluated (s).
    at, coi : str
        As `monte_carlo`.

    Returns
    -------
    dict
        {estimator: {metric: {"mean", "std", "min", "max", "runs": [one value]}}}, "std"
        None (one run: no spread).

    Raises
    ------
    InputError
        As `stabctl.estimation.pmu.stream_of_frames` and `errors`.
    """
    pmus = machine_pmus(case, at)
    truth = phasor_truth(case, result, pmus, settings.window_cycles)
    stream = stream_of_frames(frames, truth, settings, seed)
    return _stream_figures(case, result, pmus, [stream], window, coi)


def _stream_figures(case, result, pmus, streams, window, coi, done=None) -> dict:
    """Every estimator's errors on each stream, summarised over the streams; ``done()``
    after each stream's, if given."""
    models = machine_models(case, pmus)
    per_run: dict[str, list] = {name: [] for name in ESTIMATORS}
    for stream in streams:
        for name, track in run_estimators(stream, models).items():
            per_run[name].append(errors(track, result, stream, window, coi))
        if done is not None:
            done()
    return {
        name: {m: _summary([e[m] for e in rows]) for m in METRICS} for name, rows in per_run.items()
    }


def _summary(values) -> dict:
    """Mean, standard deviation (None from fewer than two runs: no spread), range and
    values of a metric over the runs (NaN: a run that gave none, left out)."""
    v = np.asarray(values, float)
    if np.all(np.isnan(v)):
        return {"mean": None, "std": None, "min": None, "max": None, "runs": [None] * v.size}
    return {
        "mean": float(np.nanmean(v)),
        "std": float(np.nanstd(v)) if np.count_nonzero(~np.isnan(v)) > 1 else None,
        "min": float(np.nanmin(v)),
        "max": float(np.nanmax(v)),
        "runs": [float(x) for x in v],
    }


def false_actions(
    case: Case,
    results,
    settings: PMUSettings,
    seed: int,
    controller: law.BangBangCOI = law.BangBangCOI(),
    at: str = "terminal",
) -> dict:
    """ESD actions of every estimator on runs without fault (module docstring).

    results: the runs without fault (e.g. with ambient load fluctuation,
    `stabctl.estimation.ambient.simulate`); run r is measured with PMU noise seed seed + r.
    Returns {estimate: {"actions": summary of the actions per run, "max_rel_mhz": of the
    largest |f_i - f_COI| seen, "std_rel_mhz": of the largest standard deviation of a
    machine's f_i - f_COI over the run}}; "true" uses the simulated speeds (its
    std_rel_mhz is the ambient spread itself); a run in which an estimator estimated
    nothing (every frame lost) gives it no figure (None in the summary when no run does).
    Raises InputError without a run.
    """
    if not results:
        raise InputError("need at least one run without fault")
    pmus = machine_pmus(case, at)
    models = machine_models(case, pmus)
    sa = st.pack(st.uniform_fleet(case, 1.0, controller), case, np.arange(case.n_bus))
    figs: dict[str, dict[str, list]] = {
        name: {"actions": [], "max_rel_mhz": [], "std_rel_mhz": []}
        for name in ("true", *ESTIMATORS)
    }
    for r, result in enumerate(results):
        stream = measure(
            phasor_truth(case, result, pmus, settings.window_cycles), settings, seed + r
        )
        tracks = {k: v.speed for k, v in run_estimators(stream, models).items()}
        tracks["true"] = result.speed_at(stream.t)
        for name, speed in tracks.items():
            rel = relative_speeds(speed, speed, models.inertia, controller.coi)[0]
            mhz = rel * models.f0 * 1e3
            seen = np.isfinite(mhz).any(axis=0)  # machines with an estimate at some time
            if not seen.any():  # nothing estimated: no figure, not 0 actions and 0 mHz
                for values in figs[name].values():
                    values.append(np.nan)
                continue
            figs[name]["actions"].append(_count_actions(sa, np.nan_to_num(rel)))
            figs[name]["max_rel_mhz"].append(float(np.nanmax(np.abs(mhz))))
            figs[name]["std_rel_mhz"].append(float(np.nanstd(mhz[:, seen], axis=0).max()))
    return {name: {k: _summary(v) for k, v in fig.items()} for name, fig in figs.items()}


@njit(cache=True)
def _count_actions(sa, rel):
    """Switchings from idle to a running mode under Table 3 (`storage.desired_mode`) of
    every device along its relative speed rel (n_f, n_dev) pu; without fault the bus
    voltages stay near 1 pu, above the gate."""
    n = 0
    for d in range(rel.shape[1]):
        mode = 0
        for k in range(rel.shape[0]):
            want = law.desired_mode(sa, d, mode, rel[k, d], 1.0)
            if mode == 0 and want != 0:
                n += 1
            mode = want
    return n
