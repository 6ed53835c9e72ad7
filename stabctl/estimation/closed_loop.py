"""Storage control with the speed estimator in the loop (closed-loop half of the estimation study).

The paper's ESDs (Table 3) act on f_i - f_COI.  Here they see it only through PMU frames:
at each reporting instant t_f = k / rate the simulation (`Simulator.run_commanded`) is
advanced to t_f, the frame of every generator's PMU is made from the trajectory so far
(`stabctl.estimation.pmu` model: true values at t_f plus the C37.118.1 noise of a seeded stream),
fed to an estimator, and the Table 3 modes (`stabctl.storage.devices.desired_mode`, on the
estimator's `forecast` over the latency) take effect at t_f + latency (docs/estimation.md 5).

Estimators (`ESTIMATORS`): ``ideal`` (true rotor speeds at t_f, no noise, no forecast),
``raw`` (the PMU frequency, the last valid frame held), ``kf`` (`FrequencyKF`, its estimate
held over the latency), ``ekf`` (`SwingEKF`, forecast with the swing equation).  The voltage
gate (0.8 pu) is applied by the devices themselves.  Optional ambient load fluctuation
(`stabctl.estimation.ambient`) rides on the same commanded fleet.

Frames are made incrementally: the noise of the whole run is drawn once per seed (the same
draws as `pmu.measure` gives for a run of that length), and each frame's true values come
from the last few grid points only, so a run costs O(frames).  Unlike the offline model
(centred differences on the whole trajectory), the bus frequency is causal: the mean over
the last two cycles, as a P-class PMU estimates it; a derivative at the end of the
trajectory would spike at every ESD switching and feed those spikes back.  The first frame
(t = 0, before the run has a recorded point) is skipped: the devices stay idle.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from stabctl.estimation import filters as es
from stabctl.storage import control as law
from stabctl.storage import devices as st
from stabctl.estimation.ambient import AmbientLoad
from stabctl.errors import InputError
from stabctl.network.ybus import branch_admittances
from stabctl.estimation.pmu import Frame, PhasorTruth, PMUSettings, machine_pmus, measure
from stabctl.dynamics.results import SimulationResult

ESTIMATORS = ("ideal", "raw", "kf", "ekf")
PMU_WINDOW_CYCLES = 2.0    # frequency estimation window of a P-class PMU (C37.118.1 annex)


@dataclass
class Diagnostics:
    """What the controller saw, per frame: t (n_f,) s time stamps; rel (n_f, n_mac) the
    relative speeds f_i - f_COI it acted on (Hz, the estimator's forecast to t + latency); modes
    (n_f, n_dev) the commanded modes; mac: each device's machine index; latency (s), f0
    (Hz), coi ("system" or "rest") of the loop."""

    t: np.ndarray
    rel: np.ndarray
    modes: np.ndarray
    mac: np.ndarray
    latency: float
    f0: float
    coi: str


class LoopController:
    """The `decide(t_f, partial)` callback of `Simulator.run_commanded`.

    case: the case; devices: the fleet's `StorageDevice`s; estimator: one of
    `ESTIMATORS`; settings: the PMUs (rate, noise, latency = the loop's latency); seed:
    noise stream; t_end: run end (s, the noise is drawn for frames in [0, t_end]);
    control: `BangBangCOI` giving the deadband, hysteresis and COI of Table 3 (its voltage
    gate is ignored here: the devices apply theirs); at: PMUs at the "terminal" or "hv"
    buses.
    """

    def __init__(self, case, devices, estimator: str, settings: PMUSettings, seed: int,
                 t_end: float, control: law.BangBangCOI = law.BangBangCOI(),
                 at: str = "terminal"):
        if estimator not in ESTIMATORS:
            raise InputError(f"estimator must be one of {', '.join(ESTIMATORS)}, got {estimator!r}")
        self.case, self.estimator, self.settings = case, estimator, settings
        self.coi = control.coi
        self.pmus = machine_pmus(case, at)
        self.models = es.machine_models(case, self.pmus)
        self.cols = case.bus_indices([p.bus for p in self.pmus])
        self.C = current_map(case, self.pmus)
        # the buses a frame needs: the PMU buses and those the currents are made from
        self.need = np.union1d(self.cols, np.nonzero(np.any(self.C != 0, axis=0))[0])
        self.need_cols = np.searchsorted(self.need, self.cols)
        self.C_need = self.C[:, self.need]
        self.noise = _unit_noise(self.pmus, settings, seed, t_end, case.freq_hz)
        self.sa = st.pack(st.StorageFleet(tuple(devices), replace(control, v_gate_pu=0.0)),
                          case, np.arange(case.n_bus))
        self.filter = _make_filter(estimator, self.models, settings)
        self.mode = np.zeros(len(devices), np.int64)
        self.held = np.full(self.models.n, np.nan)
        self.rows: list = []

    def __call__(self, t_f: float, partial: SimulationResult) -> np.ndarray:
        """Modes (n_dev,) to take effect at t_f + latency."""
        speed = self._speeds(t_f, partial)
        rel = es.relative_speeds(speed, speed, self.models.inertia, self.coi)[0]
        rel = np.nan_to_num(rel)
        self.mode = np.array([law.desired_mode(self.sa, d, self.mode[d], rel[self.sa.mac[d]], 1.0)
                              for d in range(self.mode.size)], np.int64)
        self.rows.append((t_f, rel * self.case.freq_hz, self.mode.copy()))
        return self.mode

    def _speeds(self, t_f: float, partial: SimulationResult) -> np.ndarray:
        """Speed estimates (n_mac,) pu for the instant the modes take effect."""
        if self.estimator == "ideal":
            return partial.speed_at(np.array([t_f]))[0]
        if partial.t.size < 2:          # the run start is not recorded yet: no frame
            return np.ones(self.models.n)
        frame = self._frame(t_f, partial)
        if self.estimator == "raw":
            f = frame.freq[self.models.pmu] / self.models.f0
            self.held = np.where(np.isfinite(f), f, self.held)
            return self.held
        self.filter.step(frame)
        return self.filter.forecast(self.settings.latency_s)[0]

    def _frame(self, t_f: float, partial: SimulationResult) -> Frame:
        """The measured frame at t_f: true values from the trajectory's tail, plus noise."""
        k = int(round(t_f * self.settings.rate))
        f0 = self.case.freq_hz
        v, i, f, rocof = _tail_truth(partial, self.cols, self.C, t_f, PMU_WINDOW_CYCLES / f0, f0,
                                     need=(self.need, self.need_cols, self.C_need))
        n = self.noise
        nan = np.where(n.valid[k], 1.0, np.nan)
        return Frame(t_f, n.valid[k], v * (1 + n.v[k]) * nan, i * (1 + n.i[k]) * nan,
                     (f + n.freq[k]) * nan, (rocof + n.rocof[k]) * nan)

    def diagnostics(self) -> Diagnostics:
        t, rel, modes = (np.array(a) for a in zip(*self.rows)) if self.rows else \
            (np.zeros(0), np.zeros((0, self.models.n)), np.zeros((0, self.mode.size), int))
        return Diagnostics(t=t, rel=rel, modes=modes, mac=np.asarray(self.sa.mac),
                           latency=self.settings.latency_s, f0=self.case.freq_hz, coi=self.coi)


def _make_filter(estimator: str, models: es.MachineModels, settings: PMUSettings):
    """The online filter of an estimator (None for ideal and raw)."""
    if estimator == "kf":
        return es.FrequencyKF(models.pmu, settings, f0=models.f0)
    if estimator == "ekf":
        return es.SwingEKF(models, settings)
    return None


def _unit_noise(pmus, settings: PMUSettings, seed: int, t_end: float, f0: float):
    """The errors of every frame in [0, t_end]: a stream measured on a constant truth
    (v = i = 1, f = ROCOF = 0), so v - 1, i - 1, freq, rocof are the errors and `valid`
    the losses, exactly as `measure` draws them for a run of that length."""
    n = len(pmus)
    one = np.ones((2, n), complex)
    truth = PhasorTruth(t=np.array([0.0, t_end]), pmus=tuple(pmus), v=one, i=one,
                        freq=np.zeros((2, n)), rocof=np.zeros((2, n)), f0=f0)
    s = measure(truth, settings, seed)
    return replace(s, v=np.nan_to_num(s.v - 1), i=np.nan_to_num(s.i - 1),
                   freq=np.nan_to_num(s.freq), rocof=np.nan_to_num(s.rocof))


def current_map(case, pmus) -> np.ndarray:
    """C (n_pmu, n_bus) complex with I_pmu = C @ V_bus (pu): each machine PMU's current as
    `pmu.phasor_truth` computes it (base-case branches: Kirchhoff at the terminal bus, or
    the current through the branches from the terminal bus into the PMU's bus)."""
    ba, C = branch_admittances(case), np.zeros((len(pmus), case.n_bus), complex)
    for p, pmu in enumerate(pmus):
        term = case.bus_index(int(case.machines.bus[case.machine_index(pmu.machine)]))
        b = case.bus_index(pmu.bus)
        for j in range(ba.f.size):
            f, t = ba.f[j], ba.t[j]
            if b == term and term in (f, t):
                C[p, f] += ba.yff[j] if f == term else ba.ytf[j]
                C[p, t] += ba.yft[j] if f == term else ba.ytt[j]
            elif b != term and {f, t} == {b, term}:
                C[p, f] -= ba.ytf[j] if t == b else ba.yff[j]
                C[p, t] -= ba.ytt[j] if t == b else ba.yft[j]
        if b == term:
            C[p, term] += case.buses.gshunt[term] + 1j * case.buses.bshunt[term]
    return C


def _tail_truth(partial: SimulationResult, cols, C, t_f: float, window: float, f0: float,
                need=None):
    """Noise-free PMU values at t_f from the end of the run so far (up to the first grid
    point at or after t_f): bus voltages interpolated by magnitude and unwrapped angle, the
    currents C @ V; frequency the mean over the last `window` s (phase advance / window, a
    P-class PMU's estimate: causal, and without the one-step spikes of a derivative at the
    end of the trajectory), ROCOF the change of that frequency over one more window.
    Times before the start take the initial (steady) state.  cols: the PMU buses' indices;
    need: (buses, cols within them, C on them) to interpolate only the buses the frame
    uses (`LoopController`; default all buses), the same values at a fraction of the cost."""
    bus, cols_in, C_in = need if need is not None else (np.arange(partial.vmag.shape[1]), cols, C)
    lo = max(int(np.searchsorted(partial.t, t_f - 2 * window)) - 1, 0)
    t = partial.t[lo:]
    keep = np.r_[np.diff(t) > 0, True]
    ang = np.unwrap(partial.vang[lo:, bus][keep], axis=0)
    tk = t[keep]
    now = _interp(np.array([t_f]), tk, partial.vmag[lo:, bus][keep])[0] * \
        np.exp(1j * _interp(np.array([t_f]), tk, ang)[0])
    phase = _interp(t_f - window * np.arange(2, -1, -1.0), tk, ang[:, cols_in])
    f = f0 + np.diff(phase, axis=0) / (2 * np.pi * window)
    return now[cols_in], C_in @ now, f[1], (f[1] - f[0]) / window


def _interp(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """`numpy.interp` of every column of fp (n, m) at x (k,) -> (k, m), in one pass: the
    same formula (fp[j] + slope (x - xp[j]), clamped to the end values outside xp)."""
    if xp.size == 1:
        return np.repeat(fp[:1], x.size, axis=0)
    j = np.clip(np.searchsorted(xp, x, side="right") - 1, 0, xp.size - 2)
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])[:, None]
    out = slope * (x - xp[j])[:, None] + fp[j]
    out[x <= xp[0]] = fp[0]
    out[x >= xp[-1]] = fp[-1]
    return out


@dataclass
class ClosedLoopRun:
    """One closed-loop run: the SimulationResult (its meta["switchings"] and
    meta["storage"] as `Simulator.run_commanded` gives them) and what the controller saw."""

    result: SimulationResult
    diagnostics: Diagnostics


def run_closed_loop(sim, events, t_end: float, fleet_pct: float, estimator: str,
                    rate: float = 60.0, latency: float = 0.05, seed: int = 0, *,
                    settings: PMUSettings | None = None,
                    control: law.BangBangCOI = law.BangBangCOI(), at: str = "terminal",
                    h: float | None = None, separation_limit: float = np.pi,
                    stop_at_separation: bool = True,
                    ambient: AmbientLoad | None = None) -> ClosedLoopRun:
    """Simulate `events` to t_end (s) with ESDs of fleet_pct % of each generator's MVA at
    its HV bus, commanded by Table 3 on the relative speeds from `estimator` (frames at
    `rate` frames/s, modes effective `latency` s after each time stamp, PMU noise stream
    `seed`).  settings: the PMUs (default C37.118.1 limits; its rate and latency are
    replaced by `rate`, `latency`).  The run stops once a rotor angle is more than
    separation_limit rad from the COI unless stop_at_separation is False
    (`Simulator.run_commanded`).  ambient: load fluctuations (`stabctl.estimation.ambient`) added to
    the fleet after the ESDs (the result's `pesd` and meta["storage"] list the ESDs, then
    the loads; the ESDs' voltage gate applies to both).  Raises InputError for a bad
    estimator, rate, latency, rating; SimulationError as `Simulator.run_commanded`.
    """
    settings = replace(settings or PMUSettings(), rate=rate, latency_s=latency)
    fleet = st.uniform_fleet(sim.case, fleet_pct)
    ctrl = LoopController(sim.case, fleet.devices, estimator, settings, seed, t_end, control, at)
    frames = np.arange(int(np.floor(t_end * rate + 1e-9)) + 1) / rate
    devices, decide = fleet.devices, ctrl
    if ambient is not None:
        loads, set_points = ambient.schedule(sim.case, frames.size, rate)
        devices = devices + loads
        decide = lambda t, p: np.r_[ctrl(t, p), set_points(t)]  # noqa: E731
    gate = law.ExternalCommands(v_gate_pu=control.v_gate_pu)
    res = sim.run_commanded(events, t_end, st.StorageFleet(devices, gate), frames, decide,
                            latency=latency, h=h, separation_limit=separation_limit,
                            stop_at_separation=stop_at_separation)
    return ClosedLoopRun(res, ctrl.diagnostics())


def false_actions(run: ClosedLoopRun, deadband_hz: float = 0.1) -> int:
    """Commands from idle to a running mode that Table 3 on the true relative speed at the
    instant they take effect (time stamp + latency) would not give (idle or the opposite
    mode); commands taking effect after the run's end are not counted."""
    d, res = run.diagnostics, run.result
    t_eff = d.t + d.latency
    inside = t_eff <= res.t[-1]
    if not inside.any():
        return 0
    prev = np.vstack([np.zeros((1, d.modes.shape[1]), int), d.modes[:-1]])
    start = ((prev == 0) & (d.modes != 0))[inside]
    true = res.speed_at(t_eff[inside])
    rel = es.relative_speeds(true, true, res.inertia, d.coi)[0][:, d.mac] * d.f0
    want = np.where(rel > deadband_hz, 1, np.where(rel < -deadband_hz, -1, 0))
    return int(np.sum(start & (want != d.modes[inside])))


# -- CCT with the estimator in the loop ---------------------------------------------------

@dataclass(frozen=True)
class LoopRunner:
    """What `cct.critical_clearing_time` needs of a simulator (`.case`, `.run`), with the
    ESDs (fleet_pct % of each MVA) commanded through `run_closed_loop`."""

    sim: object
    fleet_pct: float
    estimator: str
    rate: float = 60.0
    latency: float = 0.05
    seed: int = 0

    @property
    def case(self):
        return self.sim.case

    @property
    def conventions(self) -> str:
        return self.sim.conventions

    @property
    def default_h(self) -> float:
        return self.sim.default_h

    def run(self, events, t_end, h=None, separation_limit=np.pi, stop_at_separation=True):
        """The closed-loop SimulationResult (run_closed_loop's arguments)."""
        return run_closed_loop(self.sim, events, t_end, self.fleet_pct, self.estimator,
                               self.rate, self.latency, self.seed, h=h,
                               separation_limit=separation_limit,
                               stop_at_separation=stop_at_separation).result


def cct_job(case: str, bus: int, far_bus: int, esd_pct: float, estimator: str, seed: int,
            rate: float = 60.0, latency: float = 0.05, t_fault: float = 1.0,
            tol: float = 1 / 240, conventions: str = "ieee", h: float | None = None) -> dict:
    """Worker entry (`stabctl.parallel`): CCT (s, cycles) of a line fault with the estimator
    in the loop, PMU noise stream `seed`, model conventions and step h (None: default).
    The step's error bar is not searched here (the seed spread is the error bar of these
    CCTs; `stabctl cct` gives the ideal-measurement one)."""
    from stabctl.stability.cct import LineFault, cached_simulator, critical_clearing_time

    runner = LoopRunner(cached_simulator(case, conventions, h), esd_pct, estimator, rate,
                        latency, seed)
    r = critical_clearing_time(runner, LineFault(int(bus), int(far_bus), float(t_fault)),
                               tol=tol, error_check=False)
    return {"cct_s": r.cct_s, "cct_cycles": r.cct_cycles, "n_simulations": r.n_simulations}


def search_from(stable_at, k: int, k_max: int) -> tuple[int, int, int]:
    """Warm-started CCT search on the clearing-time lattice: from a hint k (e.g. the ideal
    controller's or the previous seed's CCT index), step away from k (1, 2, 4, ... cells,
    within [0, k_max]) until the verdict changes, then bisect.  Returns (k_lo, k_hi =
    k_lo + 1, simulations).  Where the verdict is monotone in the clearing time (stable
    below the CCT, unstable above) this is the bracket the cold bisection of
    `stabctl.stability.cct.critical_clearing_time` finds, in 2 runs when the hint is the
    CCT instead of about log2(t_max / tol).  Raises InputError when it is unstable at zero
    clearing or still stable at k_max."""
    n = [0]

    def probe(j: int) -> bool:
        n[0] += 1
        return stable_at(j)

    if probe(k):
        lo, step = k, 1
        while True:
            if lo == k_max:
                raise InputError(f"still stable at the search limit ({k_max} cells)")
            hi = min(lo + step, k_max)
            if not probe(hi):
                break
            lo, step = hi, 2 * step
    else:
        hi, step = k, 1
        while True:
            if hi == 0:
                raise InputError("unstable even when cleared instantly: no CCT")
            lo = max(hi - step, 0)
            if probe(lo):
                break
            hi, step = lo, 2 * step
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if probe(mid) else (lo, mid)
    return lo, hi, n[0]


def cct_chain_job(case: str, bus: int, far_bus: int, esd_pct: float, estimator: str,
                  seeds, hint_cycles: float, rate: float = 60.0, latency: float = 0.05,
                  t_fault: float = 1.0, tol: float = 1 / 240, conventions: str = "ieee",
                  h: float | None = None, t_max: float = 1.0,
                  t_after: float = 5.0) -> dict:
    """Worker entry (`stabctl.parallel`): the CCTs of `seeds` (PMU noise streams, in
    order), each searched with `search_from` from the previous seed's CCT (the first from
    hint_cycles, the ideal controller's CCT), runs stopped at separation, t_after s long
    after the fault (`stabctl.stability.cct` default 5 s).  Returns {"cct_cycles": [...],
    "n_simulations": [...], "latest_separation_s": the latest separation (s after the
    fault) of an unstable probe, the margin of the horizon}."""
    from stabctl.stability.cct import LineFault, _run, cached_simulator

    fault = LineFault(int(bus), int(far_bus), float(t_fault))
    sim = cached_simulator(case, conventions, h)
    step = sim.default_h if h is None else h
    k_max = int(np.floor(t_max / tol + 1e-9))
    k = int(round(hint_cycles / sim.case.freq_hz / tol))
    out = {"cct_cycles": [], "n_simulations": [], "latest_separation_s": 0.0}
    for seed in seeds:
        runner = LoopRunner(sim, esd_pct, estimator, rate, latency, int(seed))

        def stable_at(j: int) -> bool:
            res, diverged = _run(runner, fault, round(j * tol, 12), t_fault + t_after, step,
                                 np.pi, True, {})
            if not res.stable and res.t_separation is not None:
                out["latest_separation_s"] = max(out["latest_separation_s"],
                                                 round(res.t_separation - t_fault, 6))
            return not diverged and bool(res.stable)

        k, _, n = search_from(stable_at, k, k_max)
        out["cct_cycles"].append(round(k * tol, 12) * sim.case.freq_hz)
        out["n_simulations"].append(n)
    return out


#: Noise seeds per warm-started job of `cct_study` (a job's seeds run in order, each
#: starting from the previous seed's CCT; short jobs keep the progress bar moving).
CHAIN = 5


def cct_study(case: str, bus: int, far_bus: int, ratings, runs: int, out, *,
              estimators=ESTIMATORS, seed: int = 0, rate: float = 60.0, latency: float = 0.05,
              workers: int | None = None, progress: bool = True, conventions: str = "ieee",
              h: float | None = None, warm: bool = False, t_after: float = 5.0) -> dict:
    """CCTs per rating and estimator over `runs` noise seeds (seed .. seed + runs - 1; one
    run for "ideal", which has no noise), in parallel with `stabctl.parallel.run_sweep`
    (records appended to `out`, finished jobs reused), each by the cold bisection of
    `cct_job`.  With `warm`, only the ideal CCT is searched cold; the estimators' are
    warm-started from it (`cct_chain_job`: chains of CHAIN seeds, each from the previous
    seed's CCT), runs t_after s long after the fault.  Warm and cold searches agree where
    the verdict is monotone in the clearing time; with an estimator in the loop it need
    not be (Kundur, 20 %, raw, seed 0: stable at 53, 56 and 60 cells of 1/240 s, unstable
    at 54, 55, 57-59, 61-: the cold bisection lands on 60, a search from 72 on 53), so the
    paper's report keeps the cold search.  Returns {rating: {estimator: {"mean", "std",
    "min", "max", "runs", "failed", "values", "latest_separation_s" (warm only)}}} of the
    CCT in cycles."""
    from stabctl.parallel import Job, run_sweep

    if runs < 1:
        raise InputError(f"need at least one run, got {runs}")
    tail = ("" if conventions == "ieee" else f"/{conventions}") + ("" if h is None else f"/h{h:g}")
    if not warm:
        jobs = [Job(f"{case}/{bus}-{far_bus}/{p:g}%/{e}/{rate:g}fps/{latency:g}s/seed{s}{tail}",
                    cct_job, dict(case=case, bus=bus, far_bus=far_bus, esd_pct=p, estimator=e,
                                  seed=s, rate=rate, latency=latency, conventions=conventions,
                                  h=h))
                for p in ratings for e in estimators
                for s in ([seed] if e == "ideal" else range(seed, seed + runs))]
        rep = run_sweep(jobs, out, workers=workers, progress=progress)
        table = {}
        for j in jobs:
            rec = rep.records[j.key]
            val = rec["result"]["cct_cycles"] if rec["status"] == "ok" else np.nan
            table.setdefault(j.inputs["esd_pct"], {}).setdefault(j.inputs["estimator"],
                                                                  []).append(val)
        return {p: {e: _spread(v) for e, v in row.items()} for p, row in table.items()}
    common = dict(case=case, bus=bus, far_bus=far_bus, rate=rate, latency=latency,
                  conventions=conventions, h=h)
    stem = lambda p, e: f"{case}/{bus}-{far_bus}/{p:g}%/{e}/{rate:g}fps/{latency:g}s"  # noqa: E731
    ideal = [Job(f"{stem(p, 'ideal')}/seed{seed}{tail}", cct_job,
                 dict(common, esd_pct=p, estimator="ideal", seed=seed))
             for p in ratings]
    rep = run_sweep(ideal, out, workers=workers, progress=progress)
    table = {}
    for p, j in zip(ratings, ideal):
        rec = rep.records[j.key]
        table.setdefault(p, {})["ideal"] = [rec["result"]["cct_cycles"]
                                            if rec["status"] == "ok" else np.nan]
    chains = []
    for p, j in zip(ratings, ideal):
        hint = table[p]["ideal"][0]
        if not np.isfinite(hint):
            hint = 0.0
        for e in estimators:
            if e == "ideal":
                continue
            for a in range(seed, seed + runs, CHAIN):
                seeds = list(range(a, min(a + CHAIN, seed + runs)))
                chains.append(Job(f"{stem(p, e)}/seeds{seeds[0]}-{seeds[-1]}/warm"
                                  f"{'' if t_after == 5.0 else f'/{t_after:g}s'}{tail}",
                                  cct_chain_job,
                                  dict(common, esd_pct=p, estimator=e, seeds=seeds,
                                       hint_cycles=hint, t_after=t_after)))
    rep = run_sweep(chains, out, workers=workers, progress=progress)
    late = {}
    for j in chains:
        rec, n = rep.records[j.key], len(j.inputs["seeds"])
        ok = rec["status"] == "ok"
        vals = rec["result"]["cct_cycles"] if ok else [np.nan] * n
        key = (j.inputs["esd_pct"], j.inputs["estimator"])
        table.setdefault(key[0], {}).setdefault(key[1], []).extend(vals)
        if ok:
            late[key] = max(late.get(key, 0.0), rec["result"]["latest_separation_s"])
    return {p: {e: {**_spread(v), "latest_separation_s": late.get((p, e))}
                for e, v in row.items() if e in estimators} for p, row in table.items()}


def _spread(values) -> dict:
    """Mean, standard deviation, range of finite values (failed runs: NaN, counted)."""
    v = np.asarray(values, float)
    ok = v[np.isfinite(v)]
    stats = (float(ok.mean()), float(ok.std()), float(ok.min()), float(ok.max())) if ok.size \
        else (None,) * 4
    return {**dict(zip(("mean", "std", "min", "max"), stats)), "runs": int(v.size),
            "failed": int(v.size - ok.size), "values": [float(x) for x in v]}
