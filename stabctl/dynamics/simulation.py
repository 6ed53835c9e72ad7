"""Time-domain simulation: PST's predictor-corrector on a grid that lands on every event.

Integrator (PSTess 1.1 `s_simu.m`, docs/pst_models.md 7): explicit Heun (modified Euler),
each state advanced by x_j = x_k + h/2 (f(x_k) + f(x_k + h f(x_k))) with the network solved
at both stages.  Event times are grid points, so the run restarts exactly at every event.
The model conventions (`stabctl.dynamics.model.CONVENTIONS`, docs/conventions.md) also set the
grid and the event semantics:

- ``"ieee"`` (default): each interval between events gets ceil(length/h) equal steps (never
  longer than h) and each step uses the network of the interval it lies in ("exact"
  semantics); limiters as IEEE Std 421.5-2016.
- ``"pstess"``: PSTess's own, so that trajectories match PSTess bit for bit: fix(length/h)
  steps per interval, the corrector of the step ending at an event already uses the
  post-event network, and the first step of each interval after the first is evaluated
  once more before it is taken (its limiter clamps persist) ("pst" semantics).

Loss of synchronism: a machine's angle leaves the centre of inertia (eq. 40, weights H*MVA)
by more than `separation_limit` rad; the separated machines are the smaller coherent group
(`separated_group`); the run can stop there.  Numerical health is checked after every step
(`integrate`): a non-finite state, a speed outside [1 - SPEED_BAND, 1 + SPEED_BAND] pu or a
state that alternates in sign from step to step (the signature of an explicit method beyond
its stability region) stops the run with a NumericalInstabilityError naming the time and
the state, so that a loss of synchronism is only ever judged on a numerically healthy run.
A singular network raises SimulationError; both carry the trajectory up to that point.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from stabctl._jitcache import (assign, await_background, compile_in_background, kernel, max_abs,
                               njit)

from stabctl.dynamics import events as ev_
from stabctl.case import Case
from stabctl.storage import control as law
from stabctl.storage import devices as st
from stabctl.dynamics.coi import coi_angle, coi_value
from stabctl.dynamics.model import (BUS_VOLTAGES, NO_BUS_VOLTAGES, DynamicModel, KeptBuses,
                                    KernelNetwork, KernelOutputs, OperatingPoint,
                                    StageConfig, call_evaluate, check_conventions,
                                    evaluate_address, kernel_outputs, stacked_networks)
from stabctl.errors import InputError, NumericalInstabilityError, SimulationError
from stabctl.dynamics.results import SimulationResult


@dataclass(frozen=True)
class TimeGrid:
    """Integration grid: t (N+1,), interval id of each point (a point at an event belongs to
    the interval that starts there; a time repeats after a zero-length interval), step h
    of each interval (0 for a zero-length one), and the interval start times."""

    t: np.ndarray
    interval: np.ndarray
    h: np.ndarray
    starts: np.ndarray


def time_grid(starts, t_end: float, h: float, pstess: bool = False) -> TimeGrid:
    """The grid: intervals between consecutive start times (the first 0, non-decreasing,
    all below t_end), each divided into equal steps, at least one (so a zero-length
    interval gets one step of h = 0 and its start time appears twice, as in PSTess).
    pstess: fix(length/h) steps (PSTess, steps in [h, 2h)); else ceil(length/h) (steps at
    most h; a length within 1e-9 of a multiple of h takes that multiple).

    Raises InputError for a non-positive or non-finite step or end time.
    """
    if not (0 < h < np.inf and 0 < t_end < np.inf):
        raise InputError(f"need a positive step and end time, got h={h}, t_end={t_end}")
    pts = [float(x) for x in starts] + [float(t_end)]
    ts, ids, hs = [], [], []
    for s, (a, b) in enumerate(zip(pts[:-1], pts[1:])):
        n = max(1, int(np.trunc((b - a) / h) if pstess else np.ceil((b - a) / h - 1e-9)))
        hs.append((b - a) / n)
        ts.append(a + hs[-1] * np.arange(n))
        ids.append(np.full(n, s))
    t = np.concatenate(ts + [[pts[-1]]])
    interval = np.concatenate(ids + [[len(pts) - 2]])
    return TimeGrid(t=t, interval=interval, h=np.array(hs), starts=np.array(pts[:-1]))


#: ieee default step: at most this fraction of the fastest time constant (`default_step`).
STEP_PER_TIME_CONSTANT = 0.5


def default_step(case: Case, conventions: str = "ieee",
                 fastest: tuple[float, str] | None = None) -> float:
    """Default integration step (s).

    pstess: the data file's own step (sw_con row 1, col 7), else half a cycle of the case
    frequency (1/120 s at 60 Hz), as PSTess.  ieee: from the model, not from a PSTess run
    setting: half a cycle, capped at STEP_PER_TIME_CONSTANT times the case's fastest time
    constant, the largest step whose CCTs agree with a converged (step-halved) run within
    the 1 ms CCT tolerance on the paper's faults (docs/conventions.md, convergence table;
    docs/simulator.md, default step).  Kundur 5 ms either way (T_R = 0.01 s); miniWECC
    5 ms instead of its data file's 1/480 s (fastest 0.01 s: a governor's T_5), whose CCTs
    are the same to the millisecond (docs/simulator.md).  fastest: the case's
    `fastest_time_constant`, if already known.
    """
    sw = case.sw_con
    half_cycle = 0.5 / case.freq_hz
    if check_conventions(conventions) == "pstess":
        return float(sw[0, 6]) if sw is not None and sw[0, 6] > 0 else half_cycle
    T, _ = fastest_time_constant(case) if fastest is None else fastest
    return min(half_cycle, STEP_PER_TIME_CONSTANT * T)


_BLAS_LIMITED = False


def single_threaded_blas() -> None:
    """Limit BLAS/LAPACK to one thread in this process (once).

    The kernels solve many tiny dense systems; OpenBLAS threads make each solve 10-20 times
    slower and oversubscribe the cores when sweeps run one simulation per process.  The
    environment defaults set in `stabctl/__init__` do not reach a BLAS that numpy loaded
    before stabctl was imported, hence this run-time limit (threadpoolctl).
    """
    global _BLAS_LIMITED
    if not _BLAS_LIMITED:
        import scipy.linalg.cython_lapack  # noqa: F401  the LAPACK numba calls: load it first
        from threadpoolctl import threadpool_limits
        threadpool_limits(limits=1, user_api="blas")
        _BLAS_LIMITED = True


def fastest_time_constant(case: Case) -> tuple[float, str]:
    """Smallest time constant among the states of the case's models (s) and where it is
    (table, field, row).  Raises CaseError for models stabctl does not have."""
    from stabctl.models import exciters
    from stabctl.models import governors
    from stabctl.models import machines
    from stabctl.models import pss
    cands = []
    mp, ep = machines.machine_params(case), exciters.exciter_params(case)
    pp, gp = pss.pss_params(case), governors.governor_params(case)
    for name, arr, sel in (
            ("mac_con T\"do", mp.Tdopp, mp.kind == 2), ("mac_con T\"qo", mp.Tqopp, mp.kind == 2),
            ("mac_con T'do", mp.Tdop, mp.kind >= 1), ("mac_con T'qo", mp.Tqop, mp.kind >= 1),
            *pp.time_constants(), *ep.time_constants(), *gp.time_constants()):
        if np.any(sel):
            k = int(np.argmin(np.where(sel, np.abs(arr), np.inf)))
            cands.append((float(abs(arr[k])), f"{name} row {k + 1}"))
    return min(cands) if cands else (np.inf, "")


def check_step(fastest: tuple[float, str], h: float) -> None:
    """Raise InputError when h is not a positive finite step or exceeds twice the fastest
    time constant (`fastest_time_constant`): the explicit predictor-corrector is unstable
    there (its stability interval is h/T < 2)."""
    T, where = fastest
    if not 0 < h < np.inf:
        raise InputError(f"step must be a positive number of seconds, got {h}")
    if h >= 2 * T:
        raise InputError(f"step {h} s is too large: the fastest time constant is {T} s "
                         f"({where}); the predictor-corrector needs h < {2 * T} s")


#: most integration steps one run may take: a smaller step (or a longer run) is refused
#: at once instead of running silently for minutes and filling the memory with the
#: trajectory (miniWECC: 200000 steps are about 10 s and 0.7 GB)
MAX_STEPS = 200_000


def check_step_count(t_end: float, h: float) -> None:
    """Raise InputError when a run to t_end (s) with step h (s) needs more than MAX_STEPS
    steps."""
    if not 0 < h < float("inf"):
        raise InputError(f"step must be a finite number > 0 s, got {h}")
    n = t_end / h
    if not n <= MAX_STEPS:
        raise InputError(f"step {h:g} s: a run to {t_end:g} s needs {n:.3g} steps, more than "
                         f"the limit {MAX_STEPS} (stabctl.dynamics.simulation.MAX_STEPS); use a larger "
                         "step (--step) or a shorter run (--tf)")


class Simulator:
    """Runs disturbances on one case from its solved power flow.

    Parameters
    ----------
    case : Case
        The case (its dynamic data: machines, exciters, PSS, governors, loads).
    op : OperatingPoint or None, optional
        Its solved power flow (complex bus voltages, generation and load, pu on the
        system base); None (default): solved by
        `stabctl.network.powerflow.solve_powerflow`.
    injection_buses : sequence of int, optional
        Bus numbers kept in the reduced network of `model` for device injections
        (storage); default none.  Each run builds (and caches) the model its storage
        needs (`model_for`).
    conventions : {"ieee", "pstess"}, optional
        Model conventions (module docstring, docs/conventions.md): ``"ieee"`` (default,
        limiters as IEEE Std 421.5-2016) or ``"pstess"`` (PSTess 1.1 bit for bit).
    step : float or None, optional
        Integration step of runs that give none, s; None (default): `default_step` of
        the case and conventions.
    q_limits : bool, optional
        When `op` is None, the power flow switches PV buses to PQ at their Q limits (PST's
        ``chq_lim``, True, the default) or not (ANDES's default, ``pv2pq = 0``).
    background_compile : bool, optional
        When the integrator's kernel is neither compiled in this process nor cached,
        compile it in a child process while this one compiles the model's evaluation
        (True, the default: a cold first run then costs about the longer of the two, not
        their sum, on two cores); False for a simulator that never runs (linearisation).

    Attributes
    ----------
    default_h : float
        The step of runs that give none, s.
    model : DynamicModel
        The model keeping `injection_buses`.
    inertia : ndarray, shape (n_mac,)
        COI weights H * MVA per machine, MW s (paper eq. 40).
    fastest : tuple of (float, str)
        The case's fastest time constant (s) and where it is (`fastest_time_constant`).
    conventions : str
        ``"ieee"`` or ``"pstess"``.

    Raises
    ------
    InputError
        Unknown conventions; a step that is not positive and finite or not below twice
        the case's fastest time constant (the predictor-corrector's stability interval).
    CaseError
        Models stabctl does not have, limits violated at the initial point (as
        `stabctl.dynamics.model.DynamicModel`); UnknownBusError (a CaseError) for an
        injection bus not in the case.
    PowerFlowError
        The power flow (when `op` is None) did not converge.
    """

    def __init__(self, case: Case, op: OperatingPoint | None = None, injection_buses=(),
                 conventions: str = "ieee", step: float | None = None,
                 q_limits: bool = True, background_compile: bool = True):
        self.conventions = check_conventions(conventions)
        self.q_limits = bool(q_limits)
        if op is None:
            from stabctl.network.powerflow import solve_powerflow
            op = OperatingPoint.from_bus_matrix(
                solve_powerflow(case, q_limits=self.q_limits).bus_matrix())
        single_threaded_blas()
        self.case, self.op = case, op
        self.fastest = fastest_time_constant(case)
        self.default_h = default_step(case, conventions, self.fastest) if step is None else step
        check_step(self.fastest, self.default_h)
        self._models: dict[frozenset, DynamicModel] = {}
        self.model = self.model_for(injection_buses)
        self.inertia = self.model.mp.H * case.machines.mva
        if background_compile:
            self._compile_runs_elsewhere()

    def _compile_runs_elsewhere(self) -> None:
        """When `integrate` is neither compiled in this process nor cached, start compiling
        it in a child process for the argument types of this simulator's runs
        (`stabctl._jitcache.compile_in_background`), while this process compiles the
        model's evaluation at the first run: a cold first run takes the longer of the two
        instead of their sum.

        The child optimises at LLVM level 1 (``NUMBA_OPT=1``): `integrate` is the longer of
        the two (15.7 s instead of 16.4-19.6 s at numba's level 3, cold, on this 2-core
        machine), and its run time goes into the evaluation it calls by address, which
        stays at level 3: run times equal within noise, results bit-identical (no
        fast-math, so no level reorders floating-point arithmetic)."""
        from stabctl._jitcache import cached

        if not (integrate.signatures or cached(integrate)):
            compile_in_background(integrate, self.run_argument_types(), opt=1)

    def run_argument_types(self) -> list:
        """The numba types of `integrate`'s arguments in this simulator's runs, from a
        one-step probe run without events or storage (the types depend on neither; nothing
        is compiled).

        Returns
        -------
        list of numba types
            One per argument of `integrate`.
        """
        from numba import typeof

        m = self.model
        probe = _Run(self, m, st.pack(None, self.case, m.nc_idx),
                     time_grid([0.0], self.default_h, self.default_h),
                     [m.network(StageConfig())], False, np.pi, False)
        return [typeof(a) for a in probe.arguments(1)]

    def model_for(self, buses=()) -> DynamicModel:
        """The dynamic model keeping given buses in the reduced network (built once per set
        of buses, then cached); storage devices need their buses kept.

        Parameters
        ----------
        buses : iterable of int, optional
            Bus numbers to keep, in any order, repeats ignored; default none.

        Returns
        -------
        DynamicModel
            The case's model at this simulator's operating point and conventions.
        """
        key = frozenset(int(b) for b in buses)
        if key not in self._models:
            self._models[key] = DynamicModel(self.case, self.op, sorted(key), self.conventions)
        return self._models[key]

    def run(self, events=(), t_end: float = 5.0, h: float | None = None,
            semantics: str | None = None, separation_limit: float = np.pi,
            stop_at_separation: bool = False, storage=None) -> SimulationResult:
        """Simulate disturbances from the power-flow point, t = 0 to `t_end`.

        Parameters
        ----------
        events : iterable, optional
            `Fault`, `LineTrip`, `GeneratorTrip` and `LoadStep` events
            (`stabctl.dynamics.events`), any number, in any order; events at or after
            `t_end` do not happen.  Default none (a flat run).
        t_end : float, optional
            End of the run, s (> 0); default 5.
        h : float or None, optional
            Integration step, s; None (default): `default_h`.  Every event time is a grid
            point: under ieee each interval between events gets ceil(length/h) equal
            steps (at most h), under pstess fix(length/h) (PSTess, in [h, 2h)).
        semantics : {"pst", "exact"} or None, optional
            Event semantics (module docstring): ``"pst"``, the corrector of the step
            ending at an event uses the post-event network (PSTess); ``"exact"``, each
            step uses the network of its own interval.  None (default): "pst" under the
            pstess conventions, "exact" under ieee.
        separation_limit : float, optional
            Loss of synchronism: a rotor angle more than this from the COI angle (paper
            eq. 40), rad; default pi.
        stop_at_separation : bool, optional
            End the run at the first step after which the limit is exceeded (default
            False: run to `t_end`).
        storage : StorageFleet or None, optional
            Energy-storage devices and their controller (`stabctl.storage.devices`); their
            buses are kept in the reduced network.  None (default): no storage.

        Returns
        -------
        SimulationResult
            Trajectories of every machine and bus (and device), the loss-of-synchronism
            verdict and, with storage, the switching log and per-device figures in
            `meta`.

        Raises
        ------
        InputError
            Bad semantics, events (clearing before the fault, negative time), `t_end` or
            step (not positive and finite, too large for the case's fastest time
            constant, or more than MAX_STEPS steps).
        UnknownBusError, CaseError
            An event or storage device naming a bus, line or machine not in the case.
        NumericalInstabilityError
            The run left the integrator's stability region (names the time and the
            state).
        SimulationError
            A singular network or non-convergent loads (voltage collapse).  Both carry
            the partial result as ``.result``.
        """
        semantics = self._semantics(semantics)
        m, sa, grid, nets = self._prepare(events, t_end, h, storage, semantics)
        run = _Run(self, m, sa, grid, nets, semantics == "pst", separation_limit,
                   stop_at_separation)
        run.advance(grid.t.size - 1)
        return run.finish(storage)

    def _prepare(self, events, t_end, h, storage, semantics):
        """Validate, choose the model (storage buses kept), pack the devices, build the
        event grid and the network of every interval."""
        if semantics not in ("pst", "exact"):
            raise InputError(f"semantics must be 'pst' or 'exact', got {semantics!r}")
        events = list(events)
        ev_.validate(self.case, events, t_end)
        h = self.default_h if h is None else h
        m = self.model_for(storage.buses if storage is not None else ())
        sa = st.pack(storage, self.case, m.nc_idx)
        check_step(self.fastest, h)
        check_step_count(t_end, h)
        starts, configs = ev_.stages(self.case, events, t_end, self.op.V)
        grid = time_grid(starts, t_end, h, self.conventions == "pstess")
        return m, sa, grid, [m.network(c) for c in configs]

    def _semantics(self, semantics: str | None) -> str:
        if semantics is None:
            return "pst" if self.conventions == "pstess" else "exact"
        return semantics

    def run_commanded(self, events, t_end: float, storage, frame_times, decide,
                      latency: float = 0.0, h: float | None = None,
                      semantics: str | None = None,
                      separation_limit: float = np.pi,
                      stop_at_separation: bool = False,
                      history_s: float = 1.0) -> SimulationResult:
        """Simulate with storage devices commanded from measurements (estimator in the loop).

        At each frame time t_f (s, increasing) the run is advanced to the first grid point
        at or after t_f and ``decide(t_f, partial)`` is called with the recent trajectory
        (a SimulationResult of the last `history_s` seconds up to that grid point, so a
        measurement at t_f can be interpolated; no verdict); it returns the device set-points, which take effect at
        exactly t_f + `latency` (the step is split there) and hold until the next ones.
        With `stop_at_separation` the run ends at the first step after which a rotor angle
        is more than `separation_limit` rad from the COI, as `run` (no further frame is
        decided).

        Parameters
        ----------
        events : iterable
            Disturbances, as `run`.
        t_end : float
            End of the run, s (> 0).
        storage : StorageFleet
            The devices; its controller must be
            `stabctl.storage.control.ExternalCommands`.
        frame_times : array_like of float, shape (n_frames,)
            Measurement-frame arrival times, s, strictly increasing; those after `t_end`
            are ignored.
        decide : callable
            ``decide(t_f, partial) -> set-points``: `t_f` a float (s), `partial` a
            SimulationResult; returns array_like, shape (n_dev,), each device's set-point
            in units of its rating (Table 3 modes -1 inject, 0 idle, +1 absorb; any real
            value for a scaled power, e.g. an ambient load deviation).
        latency : float, optional
            Delay from a frame's arrival to its set-points taking effect, s (>= 0);
            default 0.
        h : float or None, optional
            Integration step, s, as `run`.
        semantics : {"pst", "exact"} or None, optional
            Event semantics, as `run`.
        separation_limit : float, optional
            Loss-of-synchronism limit, rad, as `run`; default pi.
        stop_at_separation : bool, optional
            End the run at separation, as `run`; default False.
        history_s : float, optional
            Length of the trajectory handed to `decide`, s; default 1 s (a PMU window
            is a few cycles).

        Returns
        -------
        SimulationResult
            As `run`, with the devices' powers and switching log.

        Raises
        ------
        InputError
            No fleet or a controller other than ExternalCommands, frame times not
            increasing, a negative latency; and as `run`.
        UnknownBusError, CaseError, NumericalInstabilityError, SimulationError
            As `run`.
        """
        if storage is None or storage.controller.kind != law.EXTERNAL:
            raise InputError("run_commanded needs a fleet whose controller is ExternalCommands")
        frame_times = np.asarray(frame_times, float)
        if np.any(np.diff(frame_times) <= 0) or latency < 0:
            raise InputError("frame times must increase and the latency must be >= 0")
        semantics = self._semantics(semantics)
        m, sa, grid, nets = self._prepare(events, t_end, h, storage, semantics)
        run = _Run(self, m, sa, grid, nets, semantics == "pst", separation_limit,
                   stop_at_separation, n_commands=frame_times.size)
        for i, t_f in enumerate(frame_times[frame_times <= t_end]):
            k = int(np.searchsorted(grid.t, t_f - 1e-12))
            run.advance(k)
            if run.status != OK:
                break
            run.command(i, t_f + latency,
                        np.asarray(decide(float(t_f), run.partial(k, history_s)), float))
        run.advance(grid.t.size - 1)
        return run.finish(storage)

    def _result(self, t, rec: "Recording", n, wall, limit) -> SimulationResult:
        c = self.case
        angle = rec.angle[:n]
        dev = np.abs(angle - coi_angle(angle, self.inertia)[:, None])
        lost = np.nonzero(dev.max(axis=1) > limit)[0]
        t_sep, separated = None, []
        if lost.size:
            k = int(lost[0])
            t_sep = float(t[k])
            group = separated_group(angle[k], self.inertia)
            separated = [int(x) for x in c.machines.number[group]]
        return SimulationResult(
            t=t[:n].copy(), machines=c.machines.number.astype(int), buses=c.buses.number.astype(int),
            speed=rec.speed[:n], angle=angle, pelect=rec.pelect[:n], pmech=rec.pmech[:n],
            efd=rec.efd[:n], vmag=np.abs(rec.V[:n]), vang=np.angle(rec.V[:n]),
            inertia=self.inertia, stable=t_sep is None, t_separation=t_sep, separated=separated,
            meta={"case": c.name, "conventions": self.conventions, "wall_time_s": wall,
                  "max_initial_derivative": self.model.initial_residual[0],
                  "max_initial_derivative_state": self.model.initial_residual[1]})


def simulator_cached() -> bool:
    """Whether the simulator's kernels, the integrator (`integrate`) and the model's
    evaluation (`stabctl.dynamics.model.evaluate_kernel`), are in the on-disk cache
    (`stabctl._jitcache.cached`): a new process loads them instead of compiling them."""
    from stabctl._jitcache import cached
    from stabctl.dynamics.model import evaluate_kernel

    return cached(integrate) and cached(evaluate_kernel)


class _Run:
    """One simulation in progress: the compiled loop advanced piecewise (see `integrate`)."""

    def __init__(self, sim: "Simulator", m, sa, grid, nets, pst, limit, stop, n_commands=0):
        self.sim, self.m, self.sa, self.grid = sim, m, sa, grid
        n_nc = m.V_nc0.size
        self.rec = recording(grid.t.size, m.mp.n, sim.case.n_bus, sa.pmax.size)
        self.carry = Carry(
            x=m.x0.copy(),
            kept=KeptBuses(V=m.V_nc0.copy(), held=np.zeros(n_nc, np.bool_),  # loads held low
                           S_extra=np.zeros(n_nc, np.complex128)),
            held_stage=np.full(1, -1), devices=device_state(sa, n_commands),
            health=Health(np.zeros(grid.t.size), *(np.zeros(1, np.int64) for _ in range(3))))
        self.nets, self.steps = stacked_networks(nets), step_grid(grid)
        self.opts = RunOptions(pst=pst, inertia=sim.inertia, limit=limit, stop=stop)
        self.limit = limit
        #: the model's parameters with the run's largest step as the limiters' reach
        self.params = m.params._replace(reach=float(np.max(grid.h)))
        self.k, self.status, self.wall, self.stored = 0, OK, 0.0, False
        self.evaluate: int | None = None

    @property
    def x(self) -> np.ndarray:
        """The flat state at the last stored grid index (n_state,)."""
        return self.carry.x

    @property
    def V_nc(self) -> np.ndarray:
        """The kept-bus voltages (n_nc,) complex pu."""
        return self.carry.kept.V

    def advance(self, k1: int) -> None:
        """Integrate up to grid index k1 and store its outputs (nothing after a stop);
        advance(0) at the start stores the initial point."""
        if self.status != OK or k1 < self.k or (k1 == self.k and self.stored):
            return
        self.stored = True
        if self.evaluate is None:      # the model's evaluation: compiled or loaded here
            self.evaluate = evaluate_address(self.params)
        await_background(integrate)
        wall = time.perf_counter()
        self.status, k_end = integrate(*self.arguments(k1))
        self.wall += time.perf_counter() - wall
        self.k = k_end

    def arguments(self, k1: int) -> tuple:
        """The arguments of `integrate` from the last stored grid index to k1 (an address
        of 0 before the first `advance`)."""
        return (self.carry, self.k, k1, self.steps, self.nets, self.params, self.sa,
                self.opts, self.rec, self.evaluate or 0)

    def command(self, i: int, t_apply: float, modes) -> None:
        """Schedule command i: device set-points (units of each rating) from t_apply (s)."""
        ds = self.carry.devices
        ds.cmd_t[i], ds.cmd_mode[i] = t_apply, modes

    def partial(self, k: int, history_s: float) -> SimulationResult:
        """The trajectory of the last `history_s` seconds up to grid index k (views, no
        verdict): a callback at every frame then costs the same late in a long run as
        early (the whole trajectory would make a run's cost grow with its length squared)."""
        r, c, n = self.rec, self.sim.case, k + 1
        lo = max(int(np.searchsorted(self.grid.t[:n], self.grid.t[k] - history_s)) - 1, 0)
        return SimulationResult(
            t=self.grid.t[lo:n], machines=c.machines.number.astype(int),
            buses=c.buses.number.astype(int), speed=r.speed[lo:n], angle=r.angle[lo:n],
            pelect=r.pelect[lo:n], pmech=r.pmech[lo:n], efd=r.efd[lo:n],
            vmag=np.abs(r.V[lo:n]), vang=np.angle(r.V[lo:n]), inertia=self.sim.inertia,
            devices=np.arange(1, self.sa.pmax.size + 1), pesd=self.rec.P[lo:n])

    def finish(self, storage) -> SimulationResult:
        """The result; raises SimulationError (with the partial result) after a divergence."""
        sim, g, k_end = self.sim, self.grid, self.k
        res = sim._result(g.t, self.rec, k_end + 1, self.wall, self.limit)
        if storage is not None:
            log = self.rec.log
            _attach_storage(res, storage, self.rec.P[:k_end + 1], self.rec.stats,
                            sim.case.base_mva, log[~np.isnan(log[:, 0])], sim.case.freq_hz)
        t_fail = g.t[min(k_end + 1, g.t.size - 1)]
        if self.status == UNSTABLE_STEP:
            q, x = int(self.carry.health.bad[0]), self.carry.x
            raise NumericalInstabilityError(
                f"case '{sim.case.name}': numerical instability in the step ending at t = "
                f"{t_fail:.4f} s: state {self.m.state_name(q)} = {x[q]:.6g} "
                f"({_symptom(x[q], q, self.m.mp.n)}); the step h = "
                f"{g.h[g.interval[k_end]]:.6g} s is too large for this model: use a smaller "
                f"step (trajectory kept up to {g.t[k_end]:.4f} s)", result=res)
        if self.status < 0:
            raise SimulationError(f"case '{sim.case.name}': the network/load equations did "
                                  f"not converge (voltage collapse) in the step ending at "
                                  f"t = {t_fail:.4f} s (trajectory kept up to "
                                  f"{g.t[k_end]:.4f} s)", result=res)
        return res


def _symptom(value: float, q: int, nm: int) -> str:
    if not np.isfinite(value):
        return "not finite"
    if nm <= q < 2 * nm and abs(value - 1.0) > SPEED_BAND:
        return f"speed more than {SPEED_BAND} pu from synchronous"
    return (f"the largest local error estimate, above {EST_TOL} for {EST_STEPS} steps in a "
            "row")


#: Two switchings of a device closer than this (s) count as chattering.
CHATTER_S = 0.02


def _attach_storage(res: SimulationResult, fleet, P, stats, base_mva, log, f0) -> None:
    """Device powers and per-device figures: switchings, chattering (switchings within
    CHATTER_S of the previous one), energy absorbed and delivered (MJ), highest and lowest
    stored energy relative to the start (MJ, exact at located switchings: `_advance`),
    peak power actually used (MW); the switching log (time s, device number, new mode,
    relative speed Hz) in res.meta["switchings"]."""
    res.devices = np.arange(1, len(fleet.devices) + 1)
    res.pesd = P
    res.meta["switchings"] = [(float(t), int(d) + 1, int(m), float(r * f0)) for t, d, m, r in log]
    res.meta["storage"] = [
        {"device": i + 1, "bus": d.bus, "machine": d.machine, "pmax_mw": d.pmax_mw,
         "switchings": int(stats[i, 0]),
         "chattering": int(np.sum(np.diff(log[log[:, 1] == i, 0]) < CHATTER_S)),
         "energy_absorbed_mj": float(stats[i, 1] * base_mva),
         "energy_delivered_mj": float(stats[i, 2] * base_mva),
         "soc_high_mj": float(stats[i, 3] * base_mva),
         "soc_low_mj": float(stats[i, 4] * base_mva),
         "peak_power_mw": float(np.abs(P[:, i]).max() * base_mva) if P.size else 0.0}
        for i, d in enumerate(fleet.devices)]


def separated_group(delta: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """Machines that lost synchronism: split the rotor angles at their largest gap into two
    coherent groups and return the indices of the group with the smaller inertia (the
    leading group on a tie), sorted."""
    order = np.argsort(delta)
    cut = int(np.argmax(np.diff(delta[order]))) + 1
    lagging, leading = order[:cut], order[cut:]
    m_lag, m_lead = inertia[lagging].sum(), inertia[leading].sum()
    group = leading if m_lead <= m_lag * (1 + 1e-9) else lagging
    return np.sort(group)


class Recording(NamedTuple):
    """Preallocated buffers filled by `integrate` (`recording`): speed, angle, pelect,
    pmech, efd (n_t, n_mac) and V (n_t, n_bus) complex at every grid index (the predictor
    stage's outputs); the device powers P (n_t, n_dev) pu; per device stats (n_dev, 5) =
    (switchings, energy absorbed, energy delivered, highest and lowest stored energy
    relative to the start, all in pu*s; `_advance`); the switching log (rows: time s,
    device, new mode, relative speed pu; NaN rows unused)."""

    speed: np.ndarray
    angle: np.ndarray
    pelect: np.ndarray
    pmech: np.ndarray
    efd: np.ndarray
    V: np.ndarray
    P: np.ndarray
    stats: np.ndarray
    log: np.ndarray


#: rows of the switching log of a run (switchings beyond it are counted, not logged)
LOG_ROWS = 4096


def recording(n_t: int, nm: int, nb: int, nd: int) -> Recording:
    """Zeroed buffers for a run.

    Parameters
    ----------
    n_t : int
        Grid points.
    nm, nb, nd : int
        Machines, buses, storage devices.

    Returns
    -------
    Recording
    """
    return Recording(speed=np.zeros((n_t, nm)), angle=np.zeros((n_t, nm)),
                     pelect=np.zeros((n_t, nm)), pmech=np.zeros((n_t, nm)),
                     efd=np.zeros((n_t, nm)), V=np.zeros((n_t, nb), np.complex128),
                     P=np.zeros((n_t, nd)), stats=np.zeros((nd, 5)),
                     log=np.full((LOG_ROWS, 4), np.nan))


OK, SEPARATED, NO_LOAD_FLOW, UNSTABLE_STEP = 0, 1, -1, -3

#: Numerical health (`_healthy`): a non-finite state, a speed more than SPEED_BAND pu from
#: synchronous, or Heun's local error estimate (`_local_error`) above EST_TOL for more than
#: EST_STEPS steps in a row marks a run that left the integrator's stability region.  On
#: the paper's faults healthy runs stay above 0.1 for at most 6 steps (a field voltage
#: reaching its ceiling inside a step); Kundur at h = 0.019 s (h/T_R = 1.9) sits above it
#: from 1.5 s on at a spurious fixed point of the method (Efd at its ceiling, 0.3-9).
SPEED_BAND, EST_TOL, EST_STEPS = 0.5, 0.1, 50


class Health(NamedTuple):
    """Numerical-health trackers of a run (`_healthy`): the local error estimate of the
    step ending at each grid index (n_t,), the state it is largest in (1,), the number of
    steps in a row above EST_TOL (1,), the offending state index (1,)."""

    est: np.ndarray
    worst: np.ndarray
    n_big: np.ndarray
    bad: np.ndarray


class DeviceState(NamedTuple):
    """Controller and device state carried across `integrate` calls (n_dev entries):
    mode (-1, 0, +1; an external set-point in units of the rating), power P (pu), power
    target, energy content e (pu*s); the command schedule of externally commanded devices:
    cmd_t (n_cmd,) times (s, inf until scheduled), cmd_mode (n_cmd, n_dev) set-points, and
    its next entry cmd_next[0]."""

    mode: np.ndarray
    P: np.ndarray
    target: np.ndarray
    e: np.ndarray
    cmd_next: np.ndarray
    cmd_t: np.ndarray
    cmd_mode: np.ndarray


def device_state(sa, n_commands: int = 0) -> DeviceState:
    """Initial device state: idle, no power, the initial energy sa.e0.

    Parameters
    ----------
    sa : stabctl.storage.devices.StorageArrays
        The packed fleet (n_dev devices).
    n_commands : int
        Room in the command schedule.

    Returns
    -------
    DeviceState
    """
    nd = sa.pmax.size
    return DeviceState(np.zeros(nd), np.zeros(nd), np.zeros(nd), sa.e0.copy(),
                       np.zeros(1, np.int64), np.full(n_commands, np.inf),
                       np.zeros((n_commands, nd)))


class StepGrid(NamedTuple):
    """The grid as `integrate` reads it (`TimeGrid`): t (n_t,) s, interval (n_t,) stage
    index of each point, h (n_stage,) step of each interval (s), first (n_t,) whether the
    step from a point is the first of an interval after the first."""

    t: np.ndarray
    interval: np.ndarray
    h: np.ndarray
    first: np.ndarray


def step_grid(grid: TimeGrid) -> StepGrid:
    """The kernel view of a `TimeGrid`.

    Parameters
    ----------
    grid : TimeGrid

    Returns
    -------
    StepGrid
    """
    return StepGrid(grid.t, grid.interval, grid.h, np.r_[False, np.diff(grid.interval) > 0])


class RunOptions(NamedTuple):
    """Settings of a run: pst event semantics (module docstring); inertia (n_mac,) the COI
    weights H * MVA; limit (rad) and stop: end the run when an angle leaves the COI by more
    than limit."""

    pst: bool
    inertia: np.ndarray
    limit: float
    stop: bool


class Carry(NamedTuple):
    """What `integrate` updates in place, so that a run can be continued: the flat state x
    (n_state,), the kept buses (`KeptBuses`: voltages, held loads, device injections),
    held_stage[0] the network stage the held loads belong to (they are cleared when it
    changes), the devices (`DeviceState`) and the numerical health (`Health`)."""

    x: np.ndarray
    kept: KeptBuses
    held_stage: np.ndarray
    devices: DeviceState
    health: Health


class _Kernel(NamedTuple):
    """What one network evaluation inside `integrate` needs (`_evaluate`)."""

    p: object
    nets: KernelNetwork
    kept: KeptBuses
    held_stage: np.ndarray
    out: KernelOutputs
    #: machine-code address of the model's evaluation (`stabctl.dynamics.model.call_evaluate`)
    evaluate: int


class _Seen(NamedTuple):
    """What the devices see at one point (n_dev each): speed relative to the COI r (pu),
    bus voltage v (pu), relative acceleration acc (pu/s)."""

    r: np.ndarray
    v: np.ndarray
    acc: np.ndarray


class _Workspace(NamedTuple):
    """Scratch arrays of `integrate`: derivatives at the step start (dx_k) and at the
    predictor (dx_j), what the devices see at the sub-step start (a) and end (b), and which
    devices switched in the current step."""

    dx_k: np.ndarray
    dx_j: np.ndarray
    a: _Seen
    b: _Seen
    switched: np.ndarray


@kernel
def _workspace(x, nd):
    return _Workspace(np.zeros_like(x), np.zeros_like(x),  # slots no kernel writes stay 0
                      _Seen(np.zeros(nd), np.zeros(nd), np.zeros(nd)),
                      _Seen(np.zeros(nd), np.zeros(nd), np.zeros(nd)), np.zeros(nd, np.bool_))


# -- health and separation -----------------------------------------------------------------

@kernel
def _local_error(x, f_k, f_j, hh, where):
    """Heun's local error estimate (the corrector minus the Euler predictor, hh/2 |f_j -
    f_k|), largest over the states relative to 1 + |x|; its state index in where[0]."""
    e = 0.0
    for q in range(x.size):
        eq = 0.5 * hh * abs(f_j[q] - f_k[q]) / (1.0 + abs(x[q]))
        if eq > e:
            e, where[0] = eq, q
    return e


@kernel
def _healthy(x, est, nm, health):
    """Numerical health after a step with local error estimate est (module docstring);
    returns False with the offending state index in health.bad[0]."""
    for q in range(x.size):
        if not np.isfinite(x[q]):
            health.bad[0] = q
            return False
    for i in range(nm):
        if abs(x[nm + i] - 1.0) > SPEED_BAND:
            health.bad[0] = nm + i
            return False
    health.n_big[0] = health.n_big[0] + 1 if est > EST_TOL else 0
    if health.n_big[0] > EST_STEPS:
        health.bad[0] = health.worst[0]
        return False
    return True


@kernel
def _separated(x, nm, opts):
    """Whether a rotor angle is more than opts.limit from the COI angle (eq. 40)."""
    return max_abs(x[:nm] - coi_value(x[:nm], opts.inertia)) > opts.limit


# -- recording -------------------------------------------------------------------------------

@kernel
def _record(rec, k, x, out, P):
    """Store grid index k: angles and speeds of x, the evaluation outputs, device powers."""
    nm = out.pelect.size
    for i in range(nm):
        rec.angle[k, i] = x[i]
        rec.speed[k, i] = x[nm + i]
    assign(rec.pelect[k], out.pelect)
    assign(rec.pmech[k], out.pmech)
    assign(rec.efd[k], out.efd)
    assign(rec.V[k], out.V_bus)
    if P.size > 0:
        assign(rec.P[k], P)


@kernel
def _log(rec, d, time_, mode, r):
    """Count a switching of device d and log it (time s, device, new mode, rel. speed)."""
    row = int(rec.stats[:, 0].sum())
    rec.stats[d, 0] += 1
    if row < rec.log.shape[0]:
        rec.log[row, 0], rec.log[row, 1], rec.log[row, 2], rec.log[row, 3] = time_, d, mode, r


# -- network solution ----------------------------------------------------------------------

@kernel
def _stage(nets, s):
    """The matrices of network stage s from the stacked ones."""
    return KernelNetwork(nets.Y11[s], nets.Y12[s], nets.Y21[s], nets.Y22[s], nets.Z22[s],
                         nets.R[s])


# The stages that evaluate the model are inlined into `integrate` at numba IR level
# (inline="always").  They call the model by address (`call_evaluate`), so none links it;
# compiled as functions of their own they still took longer: `integrate` alone compiled in
# 19.4 s instead of 17.4 s on a cold cache.  The compiled arithmetic, and so every result,
# is the same.
@kernel(inline="always")
def _evaluate(kn, x, stage, want, dx):
    """`evaluate_kernel` with the network of `stage`; the held loads are released when
    the stage changes.  Returns its iteration count (< 0: no convergence)."""
    if stage != kn.held_stage[0]:
        kn.kept.held[:] = False
        kn.held_stage[0] = stage
    return call_evaluate(kn.evaluate, x, kn.p, _stage(kn.nets, stage), kn.kept, want, dx,
                         kn.out)


@kernel
def _inject(sa, P, S):
    """Complex power drawn at the kept buses by the devices (absorbing is +)."""
    S[:] = 0.0
    for d in range(P.size):
        S[sa.pos[d]] += P[d]


# -- device control and energy accounting --------------------------------------------------

@kernel
def _targets(sa, mode, r, v, accel, out):
    """Device power set-points: bang-bang modes times ratings, or the linear law."""
    for d in range(out.size):
        if sa.kind == law.BANG_BANG:
            out[d] = mode[d] * sa.pmax[d]
        elif sa.kind == law.EXTERNAL:
            out[d] = mode[d] * sa.pmax[d] if v[d] >= sa.vgate else 0.0
        elif v[d] < sa.vgate:
            out[d] = 0.0
        else:
            out[d] = min(max(sa.Kv * r[d] + sa.Ka * accel[d], -sa.pmax[d]), sa.pmax[d])


@kernel
def _powers_now(sa, ds):
    """Device powers at once on their targets (ideal devices; lags and ramps keep them);
    returns whether any changed."""
    changed = False
    for d in range(ds.P.size):
        Pn = st.device_power(sa, d, ds.target[d], ds.P[d], ds.e[d], 0.0)
        changed = changed or Pn != ds.P[d]
        ds.P[d] = Pn
    return changed


@kernel
def _advance(sa, P, target, e, hh, stats):
    """Device powers after hh seconds; energy (SOC, absorbed, delivered) by trapezoid, and
    the extremes of the SOC relative to its start.  Sub-steps end at every located
    switching, so for ideal devices (power constant within a sub-step, the SOC linear)
    these extremes are exact, not sampled at grid points."""
    Pn = np.empty_like(P)
    for d in range(P.size):
        Pn[d] = st.device_power(sa, d, target[d], P[d], e[d], hh)
        e[d] += 0.5 * hh * (P[d] + Pn[d])
        stats[d, 1] += 0.5 * hh * (max(P[d], 0.0) + max(Pn[d], 0.0))
        stats[d, 2] += 0.5 * hh * (max(-P[d], 0.0) + max(-Pn[d], 0.0))
        soc = e[d] - sa.e0[d]
        stats[d, 3] = max(stats[d, 3], soc)
        stats[d, 4] = min(stats[d, 4], soc)
    return Pn


@kernel
def _observe(x, dx, nm, inertia, sa, V_nc, seen):
    """Relative speeds, bus voltages and relative accelerations seen by the devices."""
    law.relative_speeds(x, nm, inertia, sa, seen.r)
    law.relative_speeds(dx, nm, inertia, sa, seen.acc)
    for d in range(seen.r.size):
        seen.v[d] = abs(V_nc[sa.pos[d]])


# -- commands ------------------------------------------------------------------------------

@kernel
def _apply_commands(ds, t_now, rec, r):
    """Apply every scheduled command due by t_now (externally commanded devices); a
    change of the set-point's sign (idle, absorb, inject) is logged as a switching."""
    while ds.cmd_next[0] < ds.cmd_t.size and ds.cmd_t[ds.cmd_next[0]] <= t_now + 1e-12:
        c = ds.cmd_next[0]
        for d in range(ds.mode.size):
            if np.sign(ds.cmd_mode[c, d]) != np.sign(ds.mode[d]):
                _log(rec, d, ds.cmd_t[c], np.sign(ds.cmd_mode[c, d]), r[d])
            ds.mode[d] = ds.cmd_mode[c, d]
        ds.cmd_next[0] += 1


@kernel
def _substep_length(grid, sa, ds, k, rem):
    """Length of the next sub-step of step k with rem seconds left: the rest, or up to the
    next scheduled command if one falls inside."""
    if (sa.kind == law.EXTERNAL and ds.cmd_next[0] < ds.cmd_t.size
            and ds.cmd_t[ds.cmd_next[0]] < grid.t[k + 1] - 1e-12):
        return max(ds.cmd_t[ds.cmd_next[0]] - (grid.t[k + 1] - rem), 0.0)
    return rem


# -- the controller at a grid point and at a split point -----------------------------------

@kernel(inline="always")
def _control_at_grid_point(kn, grid, sa, ds, opts, w, rec, x, k):
    """The controller at grid index k (events make voltages jump here): commands due,
    Table 3 modes, targets and powers; the network is solved again if a power changed."""
    _observe(x, w.dx_k, kn.p.n_mac, opts.inertia, sa, kn.kept.V, w.a)
    if sa.kind == law.EXTERNAL:
        _apply_commands(ds, grid.t[k], rec, w.a.r)
    for d in range(sa.pmax.size):
        want = law.desired_mode(sa, d, ds.mode[d], w.a.r[d], w.a.v[d])
        if sa.kind == law.BANG_BANG and want != ds.mode[d]:
            ds.mode[d] = want
            w.switched[d] = True
            _log(rec, d, grid.t[k], want, w.a.r[d])
    _targets(sa, ds.mode, w.a.r, w.a.v, w.a.acc, ds.target)
    if _powers_now(sa, ds):
        _inject(sa, ds.P, kn.kept.S_extra)
        _evaluate(kn, x, grid.interval[k], BUS_VOLTAGES, w.dx_k)


@kernel(inline="always")
def _locate_switching(kn, grid, sa, ds, opts, w, x_b, k):
    """First bang-bang switching inside the step from grid index k (state x_b and w.dx_j at
    its end): (fraction of the step, device), (2.0, -1) if none.  A device switches at most
    once per step; a voltage-gate jump at an event is taken at the grid point."""
    _observe(x_b, w.dx_j, kn.p.n_mac, opts.inertia, sa, kn.kept.V, w.b)
    at_event = grid.interval[k + 1] != grid.interval[k]
    theta, first_d = 2.0, -1
    for d in range(sa.pmax.size):
        if w.switched[d]:    # one switching per device and step: no chattering loop
            continue
        want = law.desired_mode(sa, d, ds.mode[d], w.b.r[d], w.b.v[d])
        gate_jump = (w.a.v[d] >= sa.vgate) != (w.b.v[d] >= sa.vgate)
        if want != ds.mode[d] and not (at_event and gate_jump):  # events: at t_k+1
            th, _ = law.crossing(sa, ds.mode[d], want, w.a.r[d], w.b.r[d], w.a.v[d], w.b.v[d])
            if th < theta:
                theta, first_d = th, d
    return theta, first_d


@kernel
def _switch_located(sa, ds, w, rec, first_d, t_now):
    """At the located instant t_now: switch device first_d, and any other whose crossing
    falls there too (within 1e-9 of the step)."""
    for d in range(sa.pmax.size):
        want = law.desired_mode(sa, d, ds.mode[d], w.b.r[d], w.b.v[d])
        if want != ds.mode[d] and not w.switched[d]:
            th, new = law.crossing(sa, ds.mode[d], want, w.a.r[d], w.b.r[d], w.a.v[d], w.b.v[d])
            if d == first_d or th <= 1e-9:
                ds.mode[d] = new
                w.switched[d] = True
                _log(rec, d, t_now, new, w.a.r[d])


@kernel(inline="always")
def _resume(kn, grid, sa, ds, opts, w, rec, x_a, k, rem, first_d):
    """The controller at a split point of step k (a switching or a command, rem seconds
    before t_k+1): commands, switchings, targets, powers, then the derivatives there.
    Returns (network solved, derivatives)."""
    t_now = grid.t[k + 1] - rem
    _observe(x_a, w.dx_j, kn.p.n_mac, opts.inertia, sa, kn.kept.V, w.a)
    if sa.kind == law.EXTERNAL:
        _apply_commands(ds, t_now, rec, w.a.r)
    if first_d >= 0:
        _switch_located(sa, ds, w, rec, first_d, t_now)
    _targets(sa, ds.mode, w.a.r, w.a.v, w.a.acc, ds.target)
    _powers_now(sa, ds)
    _inject(sa, ds.P, kn.kept.S_extra)
    dx_a = np.empty_like(x_a)
    return _evaluate(kn, x_a, grid.interval[k], NO_BUS_VOLTAGES, dx_a) >= 0, dx_a


# -- the step ------------------------------------------------------------------------------

@kernel(inline="always")
def _heun(kn, sa, ds, x_a, dx_a, hh, stage, want, dx_j):
    """Heun's predictor-corrector over hh from x_a (derivatives dx_a), the devices' powers
    advanced on a copy of their energy: (network solved, corrected state); dx_j is written
    with the derivatives at the predictor (network of `stage`)."""
    Pb = _advance(sa, ds.P, ds.target, ds.e.copy(), hh, np.zeros((sa.pmax.size, 5)))
    _inject(sa, Pb, kn.kept.S_extra)
    xp = x_a + hh * dx_a
    if _evaluate(kn, xp, stage, want, dx_j) < 0:
        return False, x_a
    return True, x_a + 0.5 * hh * (dx_a + dx_j)


@kernel(inline="always")
def _substeps(kn, grid, sa, ds, opts, w, rec, health, x, k):
    """The step from grid index k, split at located switchings and scheduled commands
    (each device switches at most once per step, commands are finite: it ends).  Returns
    (status, index, state after the step; x itself when the network failed)."""
    s = grid.interval[k]
    j = grid.interval[k + 1] if opts.pst else s
    last = k == grid.interval.size - 2
    x_a, dx_a, rem = x, w.dx_k, grid.h[s]
    x_b = x
    while True:
        hh = _substep_length(grid, sa, ds, k, rem)
        ok, x_b = _heun(kn, sa, ds, x_a, dx_a, hh, j if hh == rem else s, last and hh == rem,
                        w.dx_j)
        if not ok:
            return NO_LOAD_FLOW, k, x
        if hh == rem:
            health.est[k + 1] = _local_error(x_b, dx_a, w.dx_j, hh, health.worst)
        theta, first_d = 2.0, -1
        if sa.kind == law.BANG_BANG and hh == rem:
            theta, first_d = _locate_switching(kn, grid, sa, ds, opts, w, x_b, k)
        if hh == rem and first_d < 0:
            break
        if first_d >= 0:           # re-integrate up to the first switching instant
            hh = theta * rem
        Pm = _advance(sa, ds.P, ds.target, ds.e, hh, rec.stats)
        if first_d >= 0:
            _inject(sa, Pm, kn.kept.S_extra)
            if _evaluate(kn, x_a + hh * dx_a, s, NO_BUS_VOLTAGES, w.dx_j) < 0:
                return NO_LOAD_FLOW, k, x
            x_a = x_a + 0.5 * hh * (dx_a + w.dx_j)
        else:                      # up to the scheduled command
            x_a = x_b
        rem -= hh
        assign(ds.P, Pm)
        ok, dx_a = _resume(kn, grid, sa, ds, opts, w, rec, x_a, k, rem, first_d)
        if not ok:
            return NO_LOAD_FLOW, k, x
        x_b = x_a
        if rem <= 1e-15:
            break
    if sa.pmax.size > 0 and rem > 1e-15:
        assign(ds.P, _advance(sa, ds.P, ds.target, ds.e, rem, rec.stats))
    return OK, k, x_b


@kernel(inline="always")
def _step(kn, grid, sa, ds, opts, w, rec, health, x, k):
    """One step from grid index k: the network at t_k (PSTess evaluates an interval's first
    step twice; the first pass's clamps stay), the controller there, the record of t_k,
    then the sub-steps.  Returns (status, index, state)."""
    s = grid.interval[k]
    _inject(sa, ds.P, kn.kept.S_extra)
    if grid.first[k] and opts.pst:
        V_keep = kn.kept.V.copy()
        _evaluate(kn, x, s, NO_BUS_VOLTAGES, w.dx_k)
        assign(kn.kept.V, V_keep)
    if _evaluate(kn, x, s, BUS_VOLTAGES, w.dx_k) < 0:
        return NO_LOAD_FLOW, max(k - 1, 0), x
    w.switched[:] = False
    if sa.pmax.size > 0:
        _control_at_grid_point(kn, grid, sa, ds, opts, w, rec, x, k)
    _record(rec, k, x, kn.out, ds.P)
    return _substeps(kn, grid, sa, ds, opts, w, rec, health, x, k)


@kernel(inline="always")
def _after_step(kn, sa, ds, opts, rec, health, x, k):
    """Numerical health and loss of synchronism after the step from k: (status, index)."""
    if not _healthy(x, health.est[k + 1], kn.p.n_mac, health):
        return UNSTABLE_STEP, k
    if opts.stop and _separated(x, kn.p.n_mac, opts):
        _record(rec, k + 1, x, kn.out, ds.P)
        return SEPARATED, k + 1
    return OK, k


@kernel(inline="always")
def _record_paused(kn, grid, sa, ds, rec, w, x, k1):
    """Store the outputs at k1 where a run pauses, from copies (the next call evaluates it
    for real)."""
    V_keep, held_keep, stage_keep = kn.kept.V.copy(), kn.kept.held.copy(), kn.held_stage[0]
    _inject(sa, ds.P, kn.kept.S_extra)
    _evaluate(kn, x.copy(), grid.interval[k1], BUS_VOLTAGES, w.dx_k)
    assign(kn.kept.V, V_keep)
    assign(kn.kept.held, held_keep)
    kn.held_stage[0] = stage_keep
    _record(rec, k1, x, kn.out, ds.P)


@njit
def integrate(c, k0, k1, grid, nets, p, sa, opts, rec, evaluate):
    """PST's predictor-corrector from grid index k0 to k1 (module docstring).

    Parameters
    ----------
    c : Carry
        State, kept buses, devices and health; updated in place, so that a run can be
        continued.
    k0, k1 : int
        First and last grid index.
    grid : StepGrid
        The grid (`step_grid`).
    nets : KernelNetwork
        Network matrices stacked by interval (`stabctl.dynamics.model.stacked_networks`).
    p : stabctl.dynamics.model.KernelParams
        Model parameters.
    sa : stabctl.storage.devices.StorageArrays
        The storage devices.  Bang-bang devices: a mode change within a step has its
        instant located (`stabctl.storage.control.crossing`) and the step is
        re-integrated in two parts.  Externally commanded devices: each command of the
        schedule (c.devices.cmd_t sorted) takes effect at its exact time, splitting the
        step.
    opts : RunOptions
        Event semantics, COI weights, separation limit and stop.
    rec : Recording
        Filled at every index with the predictor-stage outputs, the states, the device
        powers, their switching and energy statistics and the switching log.
    evaluate : int
        Machine-code address of `stabctl.dynamics.model.evaluate_kernel` for these
        arguments (`stabctl.dynamics.model.evaluate_address`).

    Returns
    -------
    status : int
        OK, SEPARATED (stopped at loss of synchronism), UNSTABLE_STEP (`_healthy` failed
        after the step from the index), NO_LOAD_FLOW.
    k : int
        The last stored grid index.
    """
    n = grid.interval.size
    kn = _Kernel(p, nets, c.kept, c.held_stage, kernel_outputs(p.n_mac, nets.R.shape[1]),
                 evaluate)
    w = _workspace(c.x, sa.pmax.size)
    x = c.x.copy()
    for k in range(k0, min(k1, n - 1)):
        status, k_end, x = _step(kn, grid, sa, c.devices, opts, w, rec, c.health, x, k)
        if status == OK:
            status, k_end = _after_step(kn, sa, c.devices, opts, rec, c.health, x, k)
        if status != OK:
            assign(c.x, x)
            return status, k_end
    assign(c.x, x)
    if k1 >= n - 1:
        _record(rec, n - 1, x, kn.out, c.devices.P)
        return OK, n - 1
    _record_paused(kn, grid, sa, c.devices, rec, w, x, k1)
    return OK, k1
