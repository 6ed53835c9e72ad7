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
from the last few grid points only, so a run costs O(frames).  The bus frequency and ROCOF
are the PMU's window estimates (`pmu.window_estimates`, `PMUSettings.window_cycles`, two
cycles by default) as in the offline model, but causal: over the last complete windows
before the time stamp, where the offline model centres them on it.  The first frame
(t = 0, before the run has a recorded point) is skipped: the devices stay idle.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from stabctl.dynamics.driver import CommandFrames
from stabctl.dynamics.results import SimulationResult
from stabctl.errors import (
    InputError,
    WrongTypeError,
    check_fields,
    is_whole_number,
    require_instance,
    require_items,
)
from stabctl.estimation.ambient import AmbientLoad
from stabctl.estimation.filters import FrequencyKF, SwingEKF
from stabctl.estimation.models import MachineModels, machine_models, relative_speeds
from stabctl.estimation.pmu import (
    Frame,
    PhasorTruth,
    interp_columns,
    machine_pmus,
    measure,
    window_estimates,
)
from stabctl.estimation.settings import PMUSettings, check_rate
from stabctl.estimation.sources import FILL_S
from stabctl.network.ybus import branch_admittances
from stabctl.storage import control as law
from stabctl.storage import devices as st

if TYPE_CHECKING:
    from stabctl.dynamics.driver import Simulator

ESTIMATORS = ("ideal", "raw", "kf", "ekf")
#: how frames reach the controller (`LoopOptions.transport`)
TRANSPORTS = ("process", "codec", "tcp")

#: rows of a controller's record stacked into one array (`LoopController.row`)
ROW_BLOCK = 4096
#: trajectory handed to the controller at each frame (PMU estimation windows): the two
#: windows a frame reads (`_tail_truth`) and one more of margin; a longer tail only costs time
HISTORY_WINDOWS = 3


@dataclass
class Diagnostics:
    """What the controller saw, per frame: t (n_f,) s time stamps; rel (n_f, n_mac) the
    relative speeds f_i - f_COI it acted on (Hz, the estimator's forecast to t + latency;
    nan in a frame where they could not be formed, `formed`); modes
    (n_f, n_dev) the commanded modes; freq (n_f, n_mac) the machine speeds those came from
    (Hz); age (n_f, n_mac) the seconds since each machine's last usable PMU value (0:
    measured in the frame; above 0 its speed held (raw) or predicted (kf, ekf) across a
    gap; nan: no usable value yet; 0 for the ideal estimator, which reads the true
    speeds); mac: each device's
    machine index; latency (s), f0 (Hz), coi ("system" or "rest") of the loop."""

    t: np.ndarray
    rel: np.ndarray
    modes: np.ndarray
    freq: np.ndarray
    age: np.ndarray
    mac: np.ndarray
    latency: float
    f0: float
    coi: str

    @property
    def starts(self) -> int:
        """Commands into a running mode (from idle or the opposite mode), all devices."""
        m = self.modes
        return int(((m[1:] != 0) & (m[1:] != m[:-1])).sum())

    @property
    def formed(self) -> np.ndarray:
        """(n_f,) bool: whether a frame's relative speeds could be formed, every machine's
        speed estimated (a COI needs them all); where not, `rel` is nan (the law acted
        on 0 there, which keeps the devices idle)."""
        return np.isfinite(self.freq).all(axis=1)

    def unformed(self, labels) -> str:
        """The words for the frames without relative speeds (`formed`), naming the
        machines (their PMU labels, `labels`) whose speed no frame had; '' if every frame
        has them."""
        lost = ~self.formed
        if not lost.any():
            return ""
        never = [x for x, ok in zip(labels, np.isfinite(self.freq).any(axis=0)) if not ok]
        which = f"; no estimate ever of {', '.join(never)}" if never else ""
        return (
            f"no relative speed in {lost.sum()} of {lost.size} frames (a COI needs an "
            f"estimate of every machine{which}): the devices idle there"
        )


class LoopController:
    """The `decide(t_f, partial)` callback of `Simulator.run_commanded` (`CommandFrames`).

    case: the case; devices: the fleet's `StorageDevice`s; estimator: one of
    `ESTIMATORS`; settings: the PMUs (rate, noise, latency = the loop's latency); seed:
    noise stream; t_end: run end (s, the noise is drawn for frames in [0, t_end]);
    control: `BangBangCOI` giving the deadband, hysteresis and COI of Table 3 (its voltage
    gate is ignored here: the devices apply theirs); at: PMUs at the "terminal" or "hv"
    buses.
    """

    def __init__(
        self,
        case,
        devices,
        estimator: str,
        settings: PMUSettings,
        seed: int,
        t_end: float,
        control: law.BangBangCOI = law.BangBangCOI(),
        at: str = "terminal",
    ):
        if estimator not in ESTIMATORS:
            raise InputError(f"estimator must be one of {', '.join(ESTIMATORS)}, got {estimator!r}")
        self.case, self.estimator, self.settings = case, estimator, settings
        self.coi = control.coi
        self.pmus = machine_pmus(case, at)
        self.models = machine_models(case, self.pmus)
        self.cols = case.bus_indices([p.bus for p in self.pmus])
        self.C = current_map(case, self.pmus)
        # the buses a frame needs: the PMU buses and those the currents are made from
        self.need = np.union1d(self.cols, np.nonzero(np.any(self.C != 0, axis=0))[0])
        self.need_cols = np.searchsorted(self.need, self.cols)
        self.C_need = self.C[:, self.need]
        self.noise = _unit_noise(self.pmus, settings, seed, t_end, case.freq_hz)
        self.sa = st.pack(
            st.StorageFleet(tuple(devices), replace(control, v_gate_pu=0.0)),
            case,
            np.arange(case.n_bus),
        )
        self.filter = _make_filter(estimator, self.models, settings)
        self.mode = np.zeros(len(devices), np.int64)
        #: each machine's island in the plant's network now (None: one), from the run's
        #: stages in process (`__call__`); a stream's plant does not say it
        self.island: np.ndarray | None = None
        self.held = np.full(self.models.n, np.nan)
        #: time stamp (s) of each machine's last usable PMU value (nan: none yet)
        self.seen = np.full(self.models.n, np.nan)
        self.rows: list = []  # `row`s, and blocks of them
        self._loose = 0  # rows appended since the last block
        #: frame -> frame as on the wire (transport "codec"), None: as measured
        self.wire: Callable | None = None

    def restart(self) -> None:
        """Start the estimator again, as at the first frame, and the ESDs idle, keeping
        the rows recorded (`track` after a gap in the frames too long to predict across)."""
        self.filter = _make_filter(self.estimator, self.models, self.settings)
        self.held = np.full(self.models.n, np.nan)
        self.seen = np.full(self.models.n, np.nan)
        self.mode = np.zeros_like(self.mode)

    def __call__(self, t_f: float, partial: SimulationResult) -> np.ndarray:
        """Modes (n_dev,) to take effect at t_f + latency."""
        self.island = island_at(partial, t_f)
        if self.estimator == "ideal":
            return self._command(t_f, partial.speed_at(np.array([t_f]))[0], 0.0)
        if partial.t.size < 2:  # the run start is not recorded yet: no frame
            return self._command(t_f, np.ones(self.models.n), np.nan)
        frame = self.measure(t_f, partial)
        return self.act(frame if self.wire is None else self.wire(frame))

    def act(self, frame: Frame) -> np.ndarray:
        """The controller's half: the modes (n_dev,) of a measured frame (the estimator fed
        the frame, Table 3 on its speeds for the instant the modes take effect), wherever
        the frame comes from (`measure`, or a C37.118.2 stream:
        `stabctl.estimation.c37_loop`).

        A machine whose PMU values have been unusable (absent, flagged, a clock failure)
        for more than `stabctl.estimation.sources.FILL_S` s has no speed (nan: no
        relative speed is formed, the devices idle), as a gap in the frames that long is
        not predicted across, and its estimate starts again at its next usable value
        (`filters._MachineFilters.forget`).  A prediction across 4 s of flagged values
        drove a machine to 62.8 Hz and the devices with it."""
        usable = frame.valid[self.models.pmu]
        back = usable & (frame.t - self.seen > FILL_S + 1e-9)  # lost longer than a gap
        if back.any():
            if self.estimator == "raw":
                self.held[back] = np.nan
            else:
                self.filter.forget(back)
        self.seen = np.where(usable, frame.t, self.seen)
        if self.estimator == "raw":
            f = frame.freq[self.models.pmu] / self.models.f0
            self.held = np.where(np.isfinite(f), f, self.held)
            speed = self.held
        else:
            self.filter.step(frame)
            speed = self.filter.forecast(self.settings.latency_s)[0]
        age = frame.t - self.seen
        return self._command(frame.t, np.where(age > FILL_S + 1e-9, np.nan, speed), age)

    def _command(self, t_f: float, speed: np.ndarray, age) -> np.ndarray:
        """Table 3 modes on the relative speeds of `speed` (n_mac,) pu, recorded with the
        age of each machine's value (s, a scalar or (n_mac,): `Diagnostics.age`)."""
        rel = np.nan_to_num(island_relative(speed, self.models.inertia, self.island, self.coi))
        self.mode = law.desired_modes(self.sa, self.mode, rel)
        f0 = self.case.freq_hz
        age = np.broadcast_to(np.asarray(age, float), speed.shape)
        self.rows.append(self.row(t_f, rel * f0, self.mode, np.asarray(speed) * f0, age))
        self._loose += 1
        if self._loose == ROW_BLOCK:  # a block of rows in one array (`row`)
            self.rows[-ROW_BLOCK:] = [np.vstack(self.rows[-ROW_BLOCK:])]
            self._loose = 0
        return self.mode

    @staticmethod
    def row(t_f: float, rel_hz, modes, freq_hz, age_s) -> np.ndarray:
        """A row of `diagnostics` packed in one array (t, rel (n_mac,), modes (n_dev,),
        freq (n_mac,), age (n_mac,)); `rows` holds such rows, every `ROW_BLOCK` of them
        stacked in one array (a track of millions of frames keeps about 8 bytes a value)."""
        return np.concatenate(([t_f], rel_hz, modes, freq_hz, age_s))

    def measure(self, t_f: float, partial: SimulationResult) -> Frame:
        """The PMUs' half: the measured frame at t_f, true values from the trajectory's
        tail (`partial`, at least two recorded points) plus the seed's noise."""
        k = int(round(t_f * self.settings.rate))
        f0 = self.case.freq_hz
        v, i, f, rocof = _tail_truth(
            partial,
            self.cols,
            self.C,
            t_f,
            self.settings.window_s(f0),
            f0,
            need=(self.need, self.need_cols, self.C_need),
        )
        n = self.noise
        nan = np.where(n.valid[k], 1.0, np.nan)
        return Frame(
            t_f,
            n.valid[k],
            v * (1 + n.v[k]) * nan,
            i * (1 + n.i[k]) * nan,
            (f + n.freq[k]) * nan,
            (rocof + n.rocof[k]) * nan,
        )

    def diagnostics(self) -> Diagnostics:
        n, m = self.models.n, self.mode.size
        a = np.vstack(self.rows) if self.rows else np.zeros((0, 1 + 3 * n + m))
        t, rel = a[:, 0], a[:, 1 : 1 + n]
        freq, age = a[:, 1 + n + m : 1 + 2 * n + m], a[:, 1 + 2 * n + m :]
        rel = np.where(np.isfinite(freq).all(axis=1, keepdims=True), rel, np.nan)
        modes = a[:, 1 + n : 1 + n + m].astype(np.int64)
        return Diagnostics(
            t=t,
            rel=rel,
            modes=modes,
            freq=freq,
            age=age,
            mac=np.asarray(self.sa.mac),
            latency=self.settings.latency_s,
            f0=self.case.freq_hz,
            coi=self.coi,
        )


def island_at(partial: SimulationResult, t: float) -> np.ndarray | None:
    """Each machine's island (n_mac,) int labels in the stage of the run `partial` at time
    t (`stabctl.dynamics.partition.Partition`), or None when the run has one island: a
    fault whose clearing cuts machines off the grid (Kundur's line 10-1: G1 alone)."""
    stages = [p for p in partial.partitions if p.t_s <= t + 1e-12]
    if not stages or stages[-1].island.max() == 0:
        return None
    return np.asarray(stages[-1].island)


def island_relative(
    speed: np.ndarray, inertia: np.ndarray, island: np.ndarray | None, coi: str
) -> np.ndarray:
    """omega_i - omega_COI (pu, (n_mac,)) of each machine against the COI of its island
    (`relative_speeds` within each), as the simulator's own law takes it
    (`stabctl.storage.control.relative_speeds`): 0 for a machine alone in its island or
    one that carries its island's whole weight (its devices idle).  Before, the closed
    loop took one COI of every machine, so after Kundur's line 10-1 cleared G1 alone at
    1.17 pu drove every device (round 35)."""
    if island is None:
        return relative_speeds(speed, speed, inertia, coi)[0]
    rel = np.zeros_like(np.asarray(speed, float))
    for k in np.unique(island):
        m = island == k
        if m.sum() < 2 or np.count_nonzero(inertia[m]) < 2:
            continue  # alone, or the whole weight on one machine: no relative speed
        rel[m] = relative_speeds(speed[m], speed[m], inertia[m], coi)[0]
    return rel


def track(controller: LoopController, frames, breaks=()) -> Diagnostics:
    """The controller fed frames with no plant to act on (open loop): a recording or a
    received stream, field data included, through its estimator and Table 3, frame by
    frame in order, the estimator started again at each of `breaks`.

    Parameters
    ----------
    controller : LoopController
        A fresh controller (its estimator not yet fed); not "ideal", which needs the truth.
    frames : iterable of Frame
        One column per PMU of the controller (`LoopController.pmus`).
    breaks : sequence of int, optional
        Indices of the frames before which the estimator starts again and the ESDs go
        idle (`LoopController.restart`): after a gap in the time stamps too long to
        predict across (`sources.Received.breaks`; a filter predicting over an hour gave
        a relative speed of a kilohertz).

    Returns
    -------
    Diagnostics
        Per frame: the speeds (Hz) and relative speeds (Hz) forecast to time stamp +
        latency, and the ESD modes the law would command.

    Raises
    ------
    InputError
        The ideal estimator, or a frame of another number of PMUs.
    """
    if controller.estimator == "ideal":
        raise InputError("the ideal estimator reads the true speeds: it cannot track frames")
    n = len(controller.pmus)
    again = set(breaks)
    for k, frame in enumerate(frames):
        if frame.valid.size != n:
            raise InputError(f"a frame of {frame.valid.size} PMUs for a controller of {n}")
        if k in again:
            controller.restart()
        controller.act(frame)
    return controller.diagnostics()


def _make_filter(estimator: str, models: MachineModels, settings: PMUSettings):
    """The online filter of an estimator (None for ideal and raw)."""
    if estimator == "kf":
        return FrequencyKF(models.pmu, settings, f0=models.f0)
    if estimator == "ekf":
        return SwingEKF(models, settings)
    return None


def _unit_noise(pmus, settings: PMUSettings, seed: int, t_end: float, f0: float):
    """The errors of every frame in [0, t_end]: a stream measured on a constant truth
    (v = i = 1, f = ROCOF = 0), so v - 1, i - 1, freq, rocof are the errors and `valid`
    the losses, exactly as `measure` draws them for a run of that length."""
    n = len(pmus)
    one = np.ones((2, n), complex)
    truth = PhasorTruth(
        t=np.array([0.0, t_end]),
        pmus=tuple(pmus),
        v=one,
        i=one,
        freq=np.zeros((2, n)),
        rocof=np.zeros((2, n)),
        f0=f0,
    )
    s = measure(truth, settings, seed)
    return replace(
        s,
        v=np.nan_to_num(s.v - 1),
        i=np.nan_to_num(s.i - 1),
        freq=np.nan_to_num(s.freq),
        rocof=np.nan_to_num(s.rocof),
    )


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


def _tail_truth(
    partial: SimulationResult, cols, C, t_f: float, window: float, f0: float, need=None
):
    """Noise-free PMU values at t_f from the end of the run so far (up to the first grid
    point at or after t_f): bus voltages interpolated by magnitude and unwrapped angle, the
    currents C @ V; frequency over the last `window` s before t_f and ROCOF over the last
    two (`pmu.window_estimates` centred at t_f - window / 2 and t_f - window: causal).
    Times before the start take the initial (steady) state.  cols: the PMU buses' indices;
    need: (buses, cols within them, C on them) to interpolate only the buses the frame
    uses (`LoopController`; default all buses), the same values at a fraction of the cost."""
    bus, cols_in, C_in = need if need is not None else (np.arange(partial.vmag.shape[1]), cols, C)
    lo = max(int(np.searchsorted(partial.t, t_f - 2 * window)) - 1, 0)
    t = partial.t[lo:]
    keep = np.r_[np.diff(t) > 0, True]
    ang = np.unwrap(partial.vang[lo:, bus][keep], axis=0)
    nb = ang.shape[1]  # one interpolation for |V| and angle
    at = interp_columns(np.array([t_f]), t[keep], np.hstack((partial.vmag[lo:, bus][keep], ang)))
    now = at[0, :nb] * np.exp(1j * at[0, nb:])
    f, rocof = window_estimates(
        t[keep], ang[:, cols_in], [t_f - window / 2], [t_f - window], window, f0
    )
    return now[cols_in], C_in @ now, f[0], rocof[0]


@dataclass
class ClosedLoopRun:
    """One closed-loop run: the SimulationResult (its meta["switchings"] and
    meta["storage"] as `Simulator.run_commanded` gives them), what the controller saw, and
    over TCP the link's figures (`c37_loop.LinkStats.summary`; None in process)."""

    result: SimulationResult
    diagnostics: Diagnostics
    link: dict | None = None


@dataclass(frozen=True)
class LoopOptions:
    """The estimator in the storage control loop.

    Attributes
    ----------
    fleet_pct : float
        ESD rating, % of each generator's MVA (one ESD per generator, at its HV bus).
    estimator : str
        One of `ESTIMATORS`.
    pmu : PMUSettings
        The PMUs: frames per s (``rate``), loop latency from a time stamp to the modes
        taking effect (``latency_s``, s), noise limits and frequency window.
    seed : int
        PMU noise stream.
    control : BangBangCOI
        The Table 3 law (deadband, voltage gate, COI).
    at : str
        Where the PMUs measure: ``"terminal"`` or ``"hv"``.
    esd_model : str
        The ESDs' model, ``"ideal"`` or ``"wecc"`` (WECC batteries taking the commands as
        their plant reference, `stabctl.storage.devices.StorageFleet`).
    transport : str
        One of `TRANSPORTS`: ``"process"`` (frames handed over in memory as measured),
        ``"codec"`` (in memory, each encoded as a C37.118.2 data frame and parsed back:
        float32 phasors, FREQ to 1 mHz, DFREQ to 0.01 Hz/s) or ``"tcp"`` (the PMUs
        publish a C37.118.2 stream on loopback, the controller subscribes in a thread and
        sends the modes back, `stabctl.estimation.c37_loop`).

    Raises
    ------
    WrongTypeError
        A field of another type (`stabctl.errors.check_fields`; pmu not PMUSettings,
        control not BangBangCOI); the other values are checked where they are used
        (`run_closed_loop`).
    """

    fleet_pct: float
    estimator: str
    pmu: PMUSettings = PMUSettings()
    seed: int = 0
    control: law.BangBangCOI = law.BangBangCOI()
    at: str = "terminal"
    esd_model: str = "ideal"
    transport: str = "process"

    def __post_init__(self) -> None:
        check_fields(self)  # seed=1.5 failed in numpy, seed=True ran as seed 1
        for name, kind in (("pmu", PMUSettings), ("control", law.BangBangCOI)):
            require_instance(getattr(self, name), kind, f"LoopOptions({name})")


def run_closed_loop(
    sim,
    events,
    t_end: float,
    loop: LoopOptions,
    *,
    h: float | None = None,
    separation_limit: float = np.pi,
    stop_at_separation: bool = True,
    ambient: AmbientLoad | None = None,
    serve=None,
) -> ClosedLoopRun:
    """Simulate `events` to t_end (s) with the ESDs commanded by Table 3 on the relative
    speeds the loop's estimator gives.

    Parameters
    ----------
    sim : Simulator
    events : sequence of events
    t_end : float
        Run end, s.
    loop : LoopOptions
        Rating, estimator, PMUs (frames at ``pmu.rate`` per s, modes effective
        ``pmu.latency_s`` after each time stamp), noise seed, control law.
    h : float or None, optional
        Integration step, s (None: the simulator's).
    separation_limit : float, optional
        The run stops once a rotor angle is more than this from the COI (rad) unless
        stop_at_separation is False (`Simulator.run_commanded`).
    stop_at_separation : bool, optional
    ambient : AmbientLoad or None, optional
        Load fluctuations (`stabctl.estimation.ambient`) added to the fleet after the ESDs
        (the result's `pesd` and meta["storage"] list the ESDs, then the loads; the ESDs'
        voltage gate applies to both).
    serve : stabctl.estimation.c37_loop.Listen or None, optional
        With transport ``"tcp"``: where to wait for a controller of its own
        (`stabctl.estimation.c37_loop.serve_controller`, `stabctl pmu control`); None: a
        controller thread on a free loopback port.

    Returns
    -------
    ClosedLoopRun

    Raises
    ------
    InputError
        A bad estimator or rating; an ambient load with WECC batteries.
    SimulationError
        As `Simulator.run_commanded`.
    """
    settings, rate = loop.pmu, loop.pmu.rate
    fleet = st.uniform_fleet(sim.case, loop.fleet_pct, model=loop.esd_model)
    args = (loop.estimator, settings, loop.seed, t_end, loop.control, loop.at)
    ctrl = LoopController(sim.case, fleet.devices, *args)
    frames = np.arange(int(np.floor(t_end * rate + 1e-9)) + 1) / rate
    devices = fleet.devices
    decide: Callable = ctrl
    if ambient is not None:
        if fleet.model != "ideal":
            raise InputError("an ambient load fluctuation runs with ideal ESDs only")
        loads, set_points = ambient.schedule(sim.case, frames.size, rate)
        devices = devices + loads
        decide = lambda t, p: np.r_[ctrl(t, p), set_points(t)]  # noqa: E731
    gate = law.ExternalCommands(v_gate_pu=loop.control.v_gate_pu)
    history = HISTORY_WINDOWS * settings.window_s(sim.case.freq_hz)
    run = lambda decide: sim.run_commanded(  # noqa: E731
        events,
        t_end,
        st.StorageFleet(devices, gate, model=fleet.model),
        CommandFrames(frames, decide, latency=settings.latency_s, history_s=history),
        h=h,
        separation_limit=separation_limit,
        stop_at_separation=stop_at_separation,
    )
    if loop.transport == "tcp":
        if ambient is not None:
            raise InputError("an ambient load fluctuation runs with the loop in process only")
        return _over_tcp(run, ctrl, lambda: LoopController(sim.case, fleet.devices, *args), serve)
    if loop.transport == "codec":
        from stabctl.estimation import c37

        ctrl.wire = c37.codec(c37.stream_config(sim.case, ctrl.pmus, settings.rate))
    elif loop.transport != "process":
        raise InputError(
            f"transport must be one of {', '.join(TRANSPORTS)}, got {loop.transport!r}"
        )
    return ClosedLoopRun(run(decide), ctrl.diagnostics())


def _over_tcp(run, plant: LoopController, remote_of, serve) -> ClosedLoopRun:
    """`run` with the plant's frames sent over TCP to a controller and its modes sent
    back: a second `LoopController` from remote_of() in a thread on loopback, or with
    serve (`c37_loop.Listen`) whichever controller connects there.  The diagnostics
    are the thread's (speeds included) or the plant's (modes only, speeds NaN)."""
    from stabctl.estimation import c37, c37_loop

    if plant.estimator == "ideal":
        raise InputError("the ideal estimator reads the true speeds: it has no PMU stream")
    cfg = c37.stream_config(plant.case, plant.pmus, plant.settings.rate)
    where = serve or c37_loop.Listen()
    link = c37_loop.PlantLink(
        plant, cfg, where.host, where.port, where.timeout, where.speed, where.allow
    )
    with link:
        if serve is None:
            remote = remote_of()
            thread, errors = c37_loop.controller_thread(remote, cfg, link.address)
        elif serve.on_listen is not None:
            serve.on_listen(link.address)
        res = run(link)
        link.finish(float(res.t[-1]))
    if serve is None:
        thread.join(timeout=30)
        if errors:
            raise errors[0]
        remote.rows[:0] = plant.rows  # the instants before a frame could be made
        return ClosedLoopRun(res, remote.diagnostics(), link.stats().summary())
    nan = np.full(plant.models.n, np.nan)
    plant.rows += [plant.row(t, nan, modes, nan, nan) for t, modes in link.answers]
    summary = {**link.stats().summary(), "dropped_peers": list(link.refused)}
    return ClosedLoopRun(res, plant.diagnostics(), summary)


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
    rel = relative_speeds(true, true, res.inertia, d.coi)[0][:, d.mac] * d.f0
    want = np.where(rel > deadband_hz, 1, np.where(rel < -deadband_hz, -1, 0))
    return int(np.sum(start & (want != d.modes[inside])))


# -- CCT with the estimator in the loop ---------------------------------------------------


@dataclass(frozen=True)
class LoopRunner:
    """What `cct.critical_clearing_time` needs of a simulator (`.case`, `.run`), with the
    ESDs commanded through `run_closed_loop` as `loop` says."""

    sim: Simulator
    loop: LoopOptions

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
        return run_closed_loop(
            self.sim,
            events,
            t_end,
            self.loop,
            h=h,
            separation_limit=separation_limit,
            stop_at_separation=stop_at_separation,
        ).result


#: Clearing-time resolution of the CCT searches with the estimator in the loop (s): 1/4
#: cycle at 60 Hz, the lattice the cold bisection searches on (`cct_tol`: the case's).
CCT_TOL_S = 1 / 240


def cct_tol(freq_hz: float) -> float:
    """The clearing-time resolution (s) of a case of nominal frequency `freq_hz` (Hz): a
    quarter cycle (60 Hz: `CCT_TOL_S`, 4.17 ms; 50 Hz: 5 ms, where 1/240 s was 0.208
    cycle and the CCTs fell off the quarter-cycle lattice)."""
    return CCT_TOL_S if freq_hz == 60.0 else 0.25 / freq_hz


def cct_job(inputs: dict) -> dict:
    """Worker entry (`stabctl.parallel`): CCT (s, cycles) of a line fault with the estimator
    in the loop.

    Parameters
    ----------
    inputs : dict
        The job's recorded inputs (`cct_study`): case, bus, far_bus, esd_pct, estimator,
        seed (PMU noise stream), rate (frames/s), latency (s), window_cycles (the PMUs'
        frequency window, default 2), conventions, h (step, None: default), q_limits
        (default True), t_fault (s, default 1) and tol (s, default `CCT_TOL_S`).

    Returns
    -------
    dict
        cct_s, cct_cycles, n_simulations.

    Notes
    -----
    The step's error bar is not searched here (the seed spread is the error bar of these
    CCTs; `stabctl cct` gives the ideal-measurement one).  The CCT is the cold
    bisection's (`stabctl.stability.cct.critical_clearing_time`, the search of the ideal
    row).  With an estimator in the loop the verdict need not be monotone in the clearing
    time: Kundur, 20 % ESDs, raw PMU frequency, seed 0 is stable at 53, 56 and 60 cells of
    1/240 s and unstable at 54, 55 and 57-59; the bisection reports 60 cells (15 cycles),
    the longest clearing with every shorter one stable is 53.  A search started elsewhere
    (from a neighbouring seed's CCT) can land on another stable island, so every seed is
    searched from scratch.
    """
    from stabctl.dynamics.options import ModelOptions
    from stabctl.stability.cct import (
        LineFault,
        SearchOptions,
        cached_simulator,
        critical_clearing_time,
    )

    pmu = PMUSettings(
        rate=inputs.get("rate", 60.0),
        latency_s=inputs.get("latency", 0.05),
        window_cycles=inputs.get("window_cycles", PMUSettings.window_cycles),
    )
    loop = LoopOptions(
        inputs["esd_pct"],
        inputs["estimator"],
        pmu,
        inputs["seed"],
        esd_model=inputs.get("esd_model", "ideal"),
    )
    model = ModelOptions.from_inputs(inputs)
    sim = cached_simulator(inputs["case"], model, digest=inputs.get("case_digest"))
    runner = LoopRunner(sim, loop)
    fault = LineFault(int(inputs["bus"]), int(inputs["far_bus"]), float(inputs.get("t_fault", 1.0)))
    r = critical_clearing_time(
        runner, fault, SearchOptions(tol=inputs.get("tol", CCT_TOL_S), error_check=False)
    )
    return {"cct_s": r.cct_s, "cct_cycles": r.cct_cycles, "n_simulations": r.n_simulations}


@dataclass(frozen=True)
class SeedRule:  # fields of a dataclass: numpydoc ignore=PR02
    """How many PMU noise seeds a row (rating, estimator) of `cct_study` gets: batches of
    `batch` seeds until the confidence interval of the row's mean CCT is within
    +-half_width_cycles, at most max_runs seeds.

    The half-width (`half_width`) is Student's t_{(1+c)/2, n-1} s / sqrt(n) (s the sample
    standard deviation of the n CCTs, c the confidence), but never below the lattice floor
    (1 - (1 - c)^(1/n)) tol: the CCTs lie on the search lattice (tol cycles apart), and
    when n seeds agree, a CCT one cell away has a frequency below 1 - (1 - c)^(1/n) at
    confidence c (binomial, no occurrence in n draws), which bounds the mean's shift.
    With the defaults a row whose 5 seeds agree is done (floor 0.113 cycle at tol 1/4).

    Parameters
    ----------
    batch : int
        Seeds added per round (and the first round's count), >= 1.
    max_runs : int
        Most seeds of a row, >= batch.
    half_width_cycles : float
        Target half-width of the interval (cycles).
    confidence : float
        In (0, 1).

    Raises
    ------
    InputError
        A count below 1, max_runs < batch, or a confidence outside (0, 1).
    """

    batch: int = 5
    max_runs: int = 20
    half_width_cycles: float = 0.125
    confidence: float = 0.95

    def __post_init__(self):
        if self.batch < 1 or self.max_runs < self.batch:
            raise InputError(
                f"need 1 <= batch <= max_runs seeds, got {self.batch}, {self.max_runs}"
            )
        if not 0.0 < self.confidence < 1.0:
            raise InputError(f"confidence must be in (0, 1), got {self.confidence}")

    def half_width(self, values, tol_cycles: float) -> float:
        """Half-width (cycles) of the interval of the mean of `values` (CCTs in cycles;
        NaN: a failed run, not counted); inf with fewer than two finite values."""
        from scipy.stats import t as student

        v = np.asarray(values, float)
        v = v[np.isfinite(v)]
        n = v.size
        if n < 2:
            return np.inf
        spread = student.ppf(0.5 + 0.5 * self.confidence, n - 1) * v.std(ddof=1) / np.sqrt(n)
        return float(max(spread, (1.0 - (1.0 - self.confidence) ** (1.0 / n)) * tol_cycles))


def _study_checked(fault, ratings, runs, estimators, seed, pmu, model, runner, esd_model):
    """`cct_study`'s arguments checked before any job (each failed alone in a worker, or
    was recorded as a failed run: a NaN rating, a seed of -1): its ratings, checked."""
    from stabctl.dynamics.options import ModelOptions
    from stabctl.parallel import RunnerOptions
    from stabctl.stability.cct import LineFault, checked_ratings

    for name, value, kind in (
        ("fault", fault, LineFault),
        ("pmu", pmu, PMUSettings),
        ("model", model, ModelOptions),
        ("runner", runner, RunnerOptions),
    ):
        require_instance(value, kind, f"cct_study({name})")
    if fault.far_bus is None:
        raise InputError("cct_study(fault): a line's fault is needed (far_bus), got a bus fault")
    if not isinstance(runs, SeedRule) and not is_whole_number(runs):
        raise WrongTypeError(f"cct_study(runs): a whole number or a SeedRule, got {runs!r}")
    if not isinstance(runs, SeedRule) and runs < 1:
        raise InputError(f"cct_study(runs): need at least one run, got {runs}")
    if not is_whole_number(seed) or seed < 0:
        raise InputError(f"cct_study(seed): a whole number >= 0 is needed, got {seed!r}")
    unknown = [
        e
        for e in require_items(estimators, "cct_study(estimators)", "a list")
        if e not in ESTIMATORS
    ]
    if unknown or not estimators:
        raise InputError(
            f"cct_study(estimators): of {', '.join(ESTIMATORS)}, got {list(estimators)}"
        )
    if esd_model not in st.ESD_MODELS:
        raise InputError(
            f"cct_study(esd_model): one of {', '.join(st.ESD_MODELS)}, got {esd_model!r}"
        )
    return checked_ratings(ratings, "cct_study(ratings)", none=False)


def cct_study(
    case: str,
    fault,
    ratings,
    runs,
    out,
    *,
    estimators=ESTIMATORS,
    seed: int = 0,
    pmu: PMUSettings = PMUSettings(),
    model=None,
    runner=None,
    esd_model: str = "ideal",
    label: str | None = None,
) -> dict:
    """CCTs per rating and estimator over noise seeds, each by the cold bisection of
    `cct_job`, in parallel with `stabctl.parallel.run_sweep` (records appended to `out`,
    finished jobs reused).

    Parameters
    ----------
    case : str
        A built-in case's name or a case file (`stabctl.io.load_case`; each job loads it).
    fault : LineFault
        The faulted line (fault at ``fault.bus``, at ``fault.t_fault``).
    ratings : sequence of float
        ESD ratings (% of machine MVA).
    runs : int or SeedRule
        Noise seeds per estimator row (seed .. seed + runs - 1), or a `SeedRule` choosing
        each row's count from the confidence interval of its mean.  "ideal" has no noise:
        one run.
    out : path
        The sweep's JSON-lines records.
    estimators : sequence of str
        Of `ESTIMATORS`.
    seed : int
        First noise seed.
    pmu : PMUSettings
        The PMUs' rate, latency and frequency window (each job records these three; a
        window other than the default is part of each job's key; the other fields must
        keep their defaults).
    model : ModelOptions or None
        Conventions, step and Q limits of every run (None: the defaults).
    runner : RunnerOptions or None
        Workers and progress (None: the defaults; no Dask scheduler here).
    esd_model : {"ideal", "wecc"}
        The storage devices' model (`LoopOptions.esd_model`); "wecc" jobs carry it in
        their inputs and a "/wecc" key suffix.
    label : str or None, optional
        The progress bar's name (`run_sweep`'s); default the records file's.

    Returns
    -------
    dict
        {rating: {estimator: {"mean", "std", "min", "max", "runs", "failed", "values",
        "errors", "half_width"}}}: the CCT in cycles (a failed run's value None); errors:
        the failed runs' errors, each once; half_width is the `SeedRule` half-width of the
        mean (cycles; None for a fixed count).

    Raises
    ------
    InputError
        runs below 1; PMU settings the records cannot hold, or a rate that is not one
        of the case's nominal frequency (`stabctl.estimation.settings.check_rate`,
        before any job); a rating out of (0, 100] or twice, an unknown estimator or
        device model, a seed below 0 (`_study_checked`).
    WrongTypeError
        An argument of another type (a fault not a line's LineFault, pmu, model or
        runner not their settings, a seed or a count not a whole number).
    """
    from contextlib import nullcontext

    from stabctl.dynamics.options import ModelOptions
    from stabctl.parallel import Job, RunnerOptions, default_workers, pooled, run_sweep
    from stabctl.stability.cct import compile_here, job_case

    model = ModelOptions() if model is None else model
    runner = RunnerOptions() if runner is None else runner
    ratings = _study_checked(fault, ratings, runs, estimators, seed, pmu, model, runner, esd_model)
    if replace(pmu, rate=60.0, latency_s=0.05, window_cycles=2.0) != PMUSettings():
        raise InputError(
            "the estimator CCT sweep records the PMU rate, latency and window "
            "only; keep the other PMU settings at their defaults"
        )
    rule = runs if isinstance(runs, SeedRule) else None
    seed, runs = int(seed), runs if rule else int(runs)  # 2.0 held as 2 (keys, ranges)
    loaded = job_case(case)  # the content its jobs run on in this process, and digest
    check_rate(pmu.rate, loaded.freq_hz)  # here, not as every job's failure
    tol = cct_tol(loaded.freq_hz)
    tol_cycles, digest = tol * loaded.freq_hz, loaded.digest()
    rate, latency, bus, far_bus = pmu.rate, pmu.latency_s, fault.bus, fault.far_bus
    window = (
        {}
        if pmu.window_cycles == PMUSettings.window_cycles
        else {"window_cycles": float(pmu.window_cycles)}
    )
    devices = st.model_inputs(esd_model)  # ideal: keys and inputs as before
    tail = (
        model.key_suffix()
        + "".join(f"/w{w:g}c" for w in window.values())
        + "".join(f"/{m}" for m in devices.values())
    )
    at = {} if fault.t_fault == 1.0 else {"t_fault": fault.t_fault}

    def job(p: float, e: str, s: int) -> Job:
        return Job(
            f"{case}/{bus}-{far_bus}/{p:g}%/{e}/{rate:g}fps/{latency:g}s/seed{s}{tail}",
            cct_job,
            dict(
                case=case,
                case_digest=digest,
                bus=bus,
                far_bus=far_bus,
                esd_pct=p,
                estimator=e,
                seed=s,
                rate=rate,
                latency=latency,
                **model.to_inputs(),
                **window,
                **devices,
                **at,
                **({} if tol == CCT_TOL_S else {"tol": tol}),  # 60 Hz: keys as before
            ),
        )

    compile_here(case, model)
    first = runs if rule is None else rule.batch
    count = {(p, e): 1 if e == "ideal" else first for p in ratings for e in estimators}
    n_workers = runner.workers or default_workers()
    with pooled(n_workers) if n_workers > 1 else nullcontext() as pool:  # one for all rounds
        for round_ in itertools.count(1):
            jobs = {pe: [job(*pe, s) for s in range(seed, seed + n)] for pe, n in count.items()}
            rep = run_sweep(
                [j for row in jobs.values() for j in row],
                out,
                workers=runner.workers,
                progress=runner.progress,
                pool=pool,
                # a round of more seeds has a bar of its own, named as such (round 57 AV:
                # each began again from 0 under the first's name)
                label=label
                if round_ == 1
                else f"{label or Path(out).name}: more seeds, round {round_}",
            )
            values = {
                pe: [
                    rep.records[j.key]["result"]["cct_cycles"]
                    if rep.records[j.key]["status"] == "ok"
                    else np.nan
                    for j in row
                ]
                for pe, row in jobs.items()
            }
            errors = {
                pe: sorted({rep.records[j.key].get("error", "") for j in row} - {""})
                for pe, row in jobs.items()
            }
            more = (
                {}
                if rule is None
                else {
                    pe: min(n + rule.batch, rule.max_runs)
                    for pe, n in count.items()
                    if pe[1] != "ideal"
                    and n < rule.max_runs
                    and rule.half_width(values[pe], tol_cycles) > rule.half_width_cycles
                }
            )
            if not more:
                break
            count.update(more)
    return {
        p: {
            e: {
                **_spread(values[p, e]),
                "errors": errors[p, e],
                "half_width": None
                if rule is None or e == "ideal"
                else rule.half_width(values[p, e], tol_cycles),
            }
            for e in estimators
        }
        for p in ratings
    }


def _spread(values) -> dict:
    """Mean, standard deviation (None from fewer than two: no spread), range of finite
    values (failed runs: NaN, counted; None among the values, as JSON has no NaN)."""
    v = np.asarray(values, float)
    ok = v[np.isfinite(v)]
    std = float(ok.std()) if ok.size > 1 else None
    stats = (float(ok.mean()), std, float(ok.min()), float(ok.max())) if ok.size else (None,) * 4
    return {
        **dict(zip(("mean", "std", "min", "max"), stats)),
        "runs": int(v.size),
        "failed": int(v.size - ok.size),
        "values": [float(x) if np.isfinite(x) else None for x in v],
    }
