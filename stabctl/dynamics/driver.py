"""The simulator: `Simulator` runs disturbances on one case from its solved power flow,
driving the compiled loop (`stabctl.dynamics.integrator.integrate`) piecewise (`_Run`) and
turning its recording into a `SimulationResult`.

Loss of synchronism: a machine's angle leaves the centre of inertia (eq. 40, weights H*MVA)
of its island (the machines its network joins it to before the disturbance,
`DynamicModel.island`) by more than `separation_limit` rad; the separated machines are the
smaller coherent group (`separated_group`); the run can stop there.  A machine tripped, or
cut off with its island from the main grid of its island before the disturbance (a
generator's step-up transformer opened, a system split), is out of the criterion from
that stage on, and the rest is judged against the COI of its own part of the network
(`stabctl.dynamics.partition`): the result names the machines tripped and each island
apart from the main grid with its buses and machines (lost, as PSS/E trips a generator
whose breaker opened).  The compiled loop knows each stage's islands
(`stabctl.dynamics.integrator.RunOptions`): its storage devices follow the COI of their
machine's island in the current stage, and its stop at separation judges the machines
the stage's partition judges, so a run stops where its verdict says, never for a machine
tripped or cut off from the main grid.  A run that leaves the integrator's stability
region raises NumericalInstabilityError naming the time and the state; a singular network
raises SimulationError; both carry the trajectory up to that point.
"""

from __future__ import annotations

import functools
import math
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from numbers import Real

import numpy as np

from stabctl._jit.background import await_background, compile_in_background
from stabctl._jit.cache import cached
from stabctl.case import Case, require_case
from stabctl.dynamics import events as ev_
from stabctl.dynamics import integrator as ig
from stabctl.dynamics import trapezoid
from stabctl.dynamics.bounded import BoundedCache
from stabctl.dynamics.coi import coi_of_islands
from stabctl.dynamics.grid import (
    STIFF_STEP_PER_TIME_CONSTANT,
    check_heun_growth,
    check_step,
    check_step_count,
    default_step,
    exciter_hmax,
    fastest_time_constant,
    stiff_step,
    time_grid,
)
from stabctl.dynamics.infeasible import offenders
from stabctl.dynamics.model import (
    DynamicModel,
    KeptBuses,
    OperatingPoint,
    StageConfig,
    check_conventions,
    evaluate_address,
    evaluate_kernel,
    stacked_networks,
)
from stabctl.dynamics.partition import (
    Partition,
    judged_relative,
    machine_islands_log,
    stage_at,
    stage_partitions,
    tripped_log,
)
from stabctl.dynamics.prefix import PREFIXES_KEPT, Prefix, integrate_from_cache, reach
from stabctl.dynamics.results import SimulationResult, de_energised_at
from stabctl.dynamics.switching import device_state
from stabctl.errors import (
    CaseError,
    InitialLimitError,
    InputError,
    NumericalInstabilityError,
    SimulationError,
    StabctlError,
    WrongTypeError,
    advice,
    bus_numbers,
    require_flag,
    require_items,
    require_number,
    run_on_suspect_starts,
)
from stabctl.models import converters as conv
from stabctl.network import switched_shunts as sws
from stabctl.network.solution import no_solution_hint
from stabctl.progress import run_progress
from stabctl.storage import control as law
from stabctl.storage import devices as st

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


@dataclass(frozen=True)
class CommandFrames:
    """The measurement frames of a commanded run (`Simulator.run_commanded`): when they
    arrive, what is decided at each and when the decision takes effect.

    Attributes
    ----------
    times : array_like of float, shape (n_frames,)
        Measurement-frame arrival times, s, strictly increasing; those after the run's
        end are ignored.
    decide : callable
        ``decide(t_f, partial) -> set-points``: `t_f` a float (s), `partial` a
        SimulationResult of the last `history_s` seconds up to the first grid point at or
        after t_f (no verdict); returns array_like, shape (n_dev,), each device's set-point
        in units of its rating (Table 3 modes -1 inject, 0 idle, +1 absorb; any real value
        for a scaled power, e.g. an ambient load deviation).
    latency : float, optional
        Delay from a frame's arrival to its set-points taking effect, s (>= 0); default 0.
    history_s : float, optional
        Length of the trajectory handed to `decide`, s; default 1 s (a PMU window is a
        few cycles).
    """

    times: object
    decide: Callable
    latency: float = 0.0
    history_s: float = 1.0


#: models (one per set of storage buses kept, `Simulator.model_for`) and simulators of
#: WECC battery fleets a simulator keeps: a placement study tries many
MODELS_KEPT = 8
#: the widest loss-of-synchronism limit a run takes, rad (the CLI's --separation-limit range)
MAX_SEPARATION_LIMIT_RAD = 100.0


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
        Model conventions (`stabctl.dynamics.grid`, docs/conventions.md): ``"ieee"`` (default,
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
    off_equilibrium : {"refuse", "warn"}, optional
        An initial point whose largest abs(derivative) exceeds 1e-8 (a model's
        initialisation disagreeing with its dynamics) is refused (the default) or warned
        about (`DynamicModel.check_equilibrium`, which names the state).
    suspect_starts : {"refuse", "run"}, optional
        A control whose initial point lies outside its own limits (a governor dispatched
        above its Tmax, ...) is refused (the default, `stabctl.errors.InitialLimitError`)
        or, as PSS/E runs on from its "initial conditions suspect", kept at that point,
        listed in `suspect` and in each result's ``meta["suspect_starts"]``: its limiter
        takes it to the limit at the first step, so such a case does not start at rest
        (the equilibrium check then warns instead of refusing).
    subintervals : bool, optional
        Under the ieee conventions, Heun runs integrate an exciter whose inner loop is
        faster than their step in sub-steps of its own, its inputs held over the step
        (True, the default; `stabctl.dynamics.subinterval`, PowerWorld's "sub-interval"
        option), so that the default step and the step check follow the data's time
        constants; False: one step for the whole model, which such a loop then bounds
        (the default step at half its time constant).  Never under pstess.

    Attributes
    ----------
    default_h : float
        The step of runs that give none, s.
    model : DynamicModel
        The model keeping `injection_buses`.
    inertia : ndarray, shape (n_mac,)
        COI weights H * MVA per machine, MW s (paper eq. 40; `coi_inertia`).
    island : ndarray of int, shape (n_mac,)
        Each machine's island in the case's network (`DynamicModel.island`): its COI is its
        island's.
    fastest : tuple of (float, str)
        The case's fastest time constant (s) and where it is (`fastest_time_constant`), or,
        without sub-intervals, a faster loop's at the operating point
        (`DynamicModel.fastest_loop`: an ST3's inner loop or an EXST1/ESST1A/EXAC2
        regulator with its rate feedback, `ExciterParams.inner_loop_time_constants`).
    subintervals : bool
        Whether runs integrate fast exciter loops in sub-intervals (the option, under
        ieee).
    conventions : str
        ``"ieee"`` or ``"pstess"``.
    suspect : tuple of str
        The suspect starts run on (``suspect_starts="run"``), one line each naming the
        table, row, control and the limit with the value; empty otherwise.

    Raises
    ------
    InputError
        Unknown conventions; a step that is not positive and finite or not below twice
        the case's fastest time constant (the predictor-corrector's stability interval).
    CaseError
        Models stabctl does not have, limits violated at the initial point (as
        `stabctl.dynamics.model.DynamicModel`), an initial point that is not an
        equilibrium (``off_equilibrium="refuse"``); UnknownBusError (a CaseError) for an
        injection bus not in the case.
    PowerFlowError
        The power flow (when `op` is None) did not converge.
    TypeError
        `case` is not a `Case` (`stabctl.case.require_case`); `op` not an
        `OperatingPoint`, `step` not a number, a flag not a bool
        (`stabctl.errors.WrongTypeError`).
    """

    #: `run` takes a monitor that can end a run early and runs without bus voltages (the
    #: CCT search's early verdicts and probes)
    takes_monitor = True

    def __init__(
        self,
        case: Case,
        op: OperatingPoint | None = None,
        injection_buses=(),
        conventions: str = "ieee",
        step: float | None = None,
        q_limits: bool = True,
        background_compile: bool = True,
        off_equilibrium: str = "refuse",
        suspect_starts: str = "refuse",
        subintervals: bool = True,
    ):
        case = require_case(case, "Simulator(case)")
        injection_buses = bus_numbers(injection_buses, "Simulator(injection_buses)")
        if suspect_starts not in ("refuse", "run"):
            raise InputError(f"suspect_starts must be 'refuse' or 'run', got {suspect_starts!r}")
        self.suspect_starts = suspect_starts
        self.suspect: tuple[str, ...] = ()
        self.conventions = check_conventions(conventions)
        self.q_limits = require_flag(q_limits, "Simulator(q_limits)")
        require_flag(background_compile, "Simulator(background_compile)")
        require_flag(subintervals, "Simulator(subintervals)")
        if step is not None:
            require_number(step, "Simulator(step)", "s")
        if op is not None and not isinstance(op, OperatingPoint):
            raise WrongTypeError(
                "Simulator(op): an OperatingPoint (OperatingPoint.from_bus_matrix(pf."
                f"bus_matrix()) of a solved power flow) or None is needed, got {op!r}"
            )
        given, held = case, np.zeros(0, int)
        if op is None:
            from stabctl.network.powerflow import solve_powerflow

            pf = solve_powerflow(case, q_limits=self.q_limits)
            held = case.buses.number[pf.q_limited].astype(int)
            op = OperatingPoint.from_bus_matrix(pf.bus_matrix())
            case = _with_solved_shunts(_with_solved_taps(case, pf.taps), pf.shunt_levels)
        try:
            self._start(
                case, op, injection_buses, step, background_compile, off_equilibrium, subintervals
            )
        except CaseError as exc:
            settings = dict(
                injection_buses=injection_buses,
                conventions=conventions,
                step=step,
                off_equilibrium=off_equilibrium,
                suspect_starts=suspect_starts,
                subintervals=subintervals,
            )
            hint = _held_at_q_limits(given, held, settings)
            if hint:  # the same error (its class and fields), its message completed
                exc.args = (f"{exc}{hint}", *exc.args[1:])
            raise

    def _start(
        self, case, op, injection_buses, step, background_compile, off_equilibrium, subintervals
    ) -> None:
        """The rest of the construction at the solved operating point `op` (the arguments
        as the constructor's): the model, its step, its start checked."""
        single_threaded_blas()
        self.case, self.op = case, op
        self._models: BoundedCache[DynamicModel] = BoundedCache(MODELS_KEPT)
        #: the simulators of this case with WECC batteries (`_for_storage`), and in one of
        #: them the batteries' converter rows
        self._battery_sims: BoundedCache[Simulator] = BoundedCache(MODELS_KEPT)
        #: the quiet starts of runs without commands (`stabctl.dynamics.prefix`)
        self._prefixes: BoundedCache[Prefix] = BoundedCache(PREFIXES_KEPT)
        #: the last run's stages stacked for the kernels (`stacked`)
        self._last_stack: tuple | None = None
        #: the pieces its runs' compiled loops advance in between pauses (`Pieces`)
        self._pieces = Pieces()
        self.battery_rows: np.ndarray | None = None
        self.off_equilibrium = off_equilibrium
        self.model = self.model_for(injection_buses)
        #: whether the Heun runs integrate fast exciter loops in sub-intervals (ieee only)
        self.subintervals = bool(subintervals) and self.conventions == "ieee"
        #: the fastest time constant of the data, or of a loop at the operating point that
        #: is not integrated in sub-intervals
        self.fastest = fastest_time_constant(case)
        if not self.subintervals:
            self.fastest = min(self.fastest, self.model.fastest_loop)
        self.default_h = (
            default_step(case, self.conventions, self.fastest) if step is None else step
        )
        check_step(self.fastest, self.default_h)
        self.island, self.inertia = self.model.island, self.model.coi_inertia
        if background_compile:
            self._compile_runs_elsewhere()
        self.model.check_equilibrium("warn" if self.suspect else off_equilibrium)

    def _compile_runs_elsewhere(self) -> None:
        """When `stabctl.dynamics.integrator.integrate` is neither compiled in this process
        nor cached, start compiling it in a child process for the argument types of this
        simulator's runs (`stabctl._jit.background.compile_in_background`), while this
        process compiles the model's evaluation at the first run: a cold first run takes the
        longer of the two instead of their sum.

        The child optimises at LLVM level 1 (``NUMBA_OPT=1``): `integrate` is the longer of
        the two (15.7 s instead of 16.4-19.6 s at numba's level 3, cold, on this 2-core
        machine), and its run time goes into the evaluation it calls by address, which
        stays at level 3: run times equal within noise, results bit-identical (no
        fast-math, so no level reorders floating-point arithmetic)."""
        if not (ig.integrate.signatures or cached(ig.integrate)):
            compile_in_background(ig.integrate, self.run_argument_types(), opt=1)

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
        probe = _Run(
            self,
            m,
            st.pack(None, self.case, m.nc_idx),
            time_grid([0.0], self.default_h, self.default_h),
            [m.network(StageConfig())],
            False,
            np.pi,
            False,
        )
        return [typeof(a) for a in probe.arguments(1)]

    def _stacked_stages(self, nets, bus_rows=None):
        """`stacked_networks(nets, bus_rows)`, the last one kept: the probes of a CCT search
        run the same stages (ACTIVSg2000: 2.5 ms a run to stack them, about 2 %)."""
        key = (tuple(map(id, nets)), None if bus_rows is None else bus_rows.tobytes())
        if self._last_stack is None or self._last_stack[0] != key:  # nets held: ids stay
            self._last_stack = (key, tuple(nets), stacked_networks(nets, bus_rows))
        return self._last_stack[2]

    def model_for(self, buses=()) -> DynamicModel:
        """The dynamic model keeping given buses in the reduced network (built once per set
        of buses, the MODELS_KEPT most recently used kept); storage devices need their
        buses kept.

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
        return self._models.get(key, lambda: self._build_model(sorted(key)))

    def _build_model(self, buses: list) -> DynamicModel:
        if self.suspect_starts == "refuse":
            try:
                return DynamicModel(self.case, self.op, buses, self.conventions)
            except InitialLimitError as err:
                raise _named_limits(self.case, err) from None
            except CaseError as err:
                raise _named_converter(self.case, err) from None
        with run_on_suspect_starts() as found:
            model = DynamicModel(self.case, self.op, buses, self.conventions)
        named = (line for err in found for line in offenders(self.case, err))
        self.suspect = tuple(dict.fromkeys((*self.suspect, *named)))
        return model

    def run(
        self,
        events=(),
        t_end: float = 5.0,
        h: float | None = None,
        semantics: str | None = None,
        separation_limit: float = np.pi,
        stop_at_separation: bool = False,
        storage=None,
        method: str = "heun",
        monitor: Callable[[SimulationResult], str | None] | None = None,
        voltages: bool | Sequence[int] = True,
    ) -> SimulationResult:
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
            Event semantics (`stabctl.dynamics.integrator`): ``"pst"``, the corrector of
            the step ending at an event uses the post-event network (PSTess); ``"exact"``,
            each step uses the network of its own interval.  None (default): "pst" under the
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
        method : {"heun", "trapezoid"}, optional
            Integration method: "heun" (default), the compiled predictor-corrector
            (`stabctl.dynamics.integrator`, PSTess's); "trapezoid", the implicit trapezoidal
            rule (`stabctl.dynamics.trapezoid`, ANDES's), A-stable, "exact" semantics
            only, without storage devices, a Python loop around the compiled evaluation.
        monitor : callable or None, optional
            Heun only: ``monitor(partial) -> str or None`` is called every
            `MONITOR_EVERY_S` of simulated time with the trajectory so far (a
            SimulationResult without verdict, arrays are views); a string ends the run
            there and is kept as ``meta["early_verdict"]``, the run's verdict then
            ``STOPPED`` unless it separated (the partial's vmag and vang are empty; e.g.
            `stabctl.stability.sime.EarlyVerdict`).  The trajectory up to the stop equals
            the unmonitored run's.  None (default): no monitor.
        voltages : bool or sequence of int, optional
            Heun only: record every bus voltage (default True).  False: the network
            solution computes only what the models read (the machine buses and the kept
            buses), the result's vmag and vang are (n_t, 0) and its buses empty.  Bus
            numbers: those buses' voltages only (the result's buses in the case's order;
            the placement's runs record its candidate sites').  The
            trajectories are the same to round-off: the machine buses' voltages are then
            summed from R's machine rows instead of taken from every bus's product
            (`stabctl._jit.arrays`), bit for bit where the reduced network is small
            (Kundur).  On
            ACTIVSg2000 (2000 buses, 334 machines) a run takes half the time without them
            (3.4-3.8 s instead of 7.4 s for 3 s at the default step, loaded machine) and
            16 bytes per bus per step less memory; the CCT search's probes
            (`stabctl.stability.cct`) run without them unless a custom criterion reads
            them.

        Returns
        -------
        SimulationResult
            Trajectories of every machine and bus (and device), the loss-of-synchronism
            verdict and, with storage, the switching log and per-device figures in
            `meta`.

        Raises
        ------
        InputError
            Bad semantics or method (the trapezoid with "pst" semantics or storage),
            events (clearing before the fault, negative time), `t_end` or step (not
            positive and finite, too large for the case's fastest time constant under
            Heun, or more steps than `stabctl.dynamics.grid.check_step_count` allows), a
            `separation_limit` not above every machine's angle from the COI at the start
            (`check_separation_limit`).
        UnknownBusError, CaseError
            An event, storage device or ``voltages`` naming a bus, line or machine not
            in the case.
        NumericalInstabilityError
            The run left the integrator's stability region (names the time and the
            state).
        SimulationError
            A singular network or non-convergent loads (voltage collapse).  Both carry
            the partial result as ``.result``.
        TypeError
            An event that is no event class (a str, None), `storage` not a
            `StorageFleet`; `events` not a list, `h` not a number, `monitor` not a
            function or returning neither None nor a string
            (`stabctl.errors.WrongTypeError`).
        """
        semantics = self._semantics(semantics)
        _check_method(method, semantics, storage)
        self.check_separation_limit(separation_limit)
        require_flag(stop_at_separation, "run(stop_at_separation)")
        if monitor is not None and not callable(monitor):
            raise WrongTypeError(f"run(monitor): a function or None is needed, got {monitor!r}")
        if monitor is not None and method != "heun":
            raise InputError(f"a run monitor needs the heun method, got {method!r}")
        if method == "trapezoid":  # no storage (`_check_method`): this simulator's run
            m, _, grid, nets = self._prepare(events, t_end, h, storage, semantics, method)
            parts = self.partitions(m, grid, nets)
            res = trapezoid.run(self, m, grid, nets, separation_limit, stop_at_separation, parts)
            return self._annotated(res, grid, nets, parts)
        handle = self._handle(
            events, t_end, h, semantics, separation_limit, stop_at_separation, storage, voltages
        )
        if monitor is None:
            handle.advance_to(t_end)
            return handle.result()
        verdict = _advance_monitored(handle.run, monitor)
        res = handle.result()
        if verdict is not None:
            res.meta["early_verdict"] = verdict
        return res

    def start(
        self,
        events=(),
        t_end: float = 5.0,
        h: float | None = None,
        semantics: str | None = None,
        separation_limit: float = np.pi,
        stop_at_separation: bool = False,
        storage=None,
        voltages: bool | Sequence[int] = True,
    ) -> RunHandle:
        """A Heun run of `run`, not advanced yet: its caller advances it in pieces
        (`RunHandle.advance_to`) and reads its result at any pause (`RunHandle.result`).

        The trajectory is the one `run` gives, bit for bit, wherever the run pauses: the
        grid is built to `t_end` at once and the compiled loop continues from its carry
        (`stabctl.dynamics.integrator.integrate`).  A CCT search pauses its probes some
        seconds after the clearing and continues the one it must confirm
        (`stabctl.stability.cct`).

        Parameters
        ----------
        events : iterable, optional
            Disturbances, as `run`.
        t_end : float, optional
            End of the run, s (> 0); default 5.
        h : float or None, optional
            Integration step, s, as `run`.
        semantics : {"pst", "exact"} or None, optional
            Event semantics, as `run`.
        separation_limit : float, optional
            Loss-of-synchronism limit, rad, as `run`; default pi.
        stop_at_separation : bool, optional
            End the run at separation, as `run`; default False.
        storage : StorageFleet or None, optional
            Energy-storage devices, as `run`.
        voltages : bool or sequence of int, optional
            The buses whose voltages are recorded, as `run`; default every bus.

        Returns
        -------
        RunHandle
            The run at t = 0, nothing integrated (its memory, the recording to `t_end`,
            taken).

        Raises
        ------
        InputError, UnknownBusError, CaseError
            As `run`.
        """
        return self._handle(
            events, t_end, h, semantics, separation_limit, stop_at_separation, storage, voltages
        )

    def _handle(
        self, events, t_end, h, semantics, separation_limit, stop_at_separation, storage, voltages
    ) -> RunHandle:
        """`start`'s run, which `run` advances too (a caller counting `start` counts the
        runs it pauses only)."""
        semantics = self._semantics(semantics)
        _check_method("heun", semantics, storage)
        self.check_separation_limit(separation_limit)
        sim = self._for_storage(storage)
        if sim is not self:
            return sim._handle(
                events,
                t_end,
                h,
                semantics,
                separation_limit,
                stop_at_separation,
                storage,
                voltages,
            )
        rows = voltage_rows(self.case, voltages)
        prepared = self._prepare(events, t_end, h, storage, semantics, "heun", rows)
        pst = semantics == "pst"
        run = _Run(self, *prepared, pst, separation_limit, stop_at_separation, bus_rows=rows)
        return RunHandle(run, storage)

    def _annotated(self, res: SimulationResult, grid, nets, parts) -> SimulationResult:
        """`res` with its islanding (`islanding_log`), tripped machines
        (`stabctl.dynamics.partition.tripped_log`) and suspect starts in its meta, those
        that are not empty."""
        islanded = islanding_log(grid, nets, self.case, parts)
        if islanded:
            res.meta["islanded"] = islanded
        tripped = tripped_log(parts, self.case.machines.number)
        if tripped:
            res.meta["tripped"] = tripped
        if self.suspect:
            res.meta["suspect_starts"] = list(self.suspect)
        stiff = self._stiff_log(grid, nets)
        if stiff:
            res.meta["stiff_intervals"] = stiff
        return res

    def _stiff_log(self, grid, nets) -> list[dict]:
        """The intervals of a run stepped finer than its step (`stiff_substeps`): each
        one's start and end (s), step (s) and the machine whose subtransient time
        constant (s) set it."""
        out = []
        ends = [*grid.starts[1:], grid.t[-1]]
        for k, (a, b, hh) in enumerate(zip(grid.starts, ends, grid.h)):
            if (
                self.conventions == "pstess"
                or b <= a
                or self.stiff_substeps(self.model, nets[k]) == 1
            ):
                continue
            T = self.model.subtransient_time_constants(nets[k], self.default_h)
            i = int(np.argmin(T))
            out.append(
                {
                    "t_start_s": float(a),
                    "t_end_s": float(b),
                    "step_s": float(hh),
                    "machine": int(self.case.machines.number[i]),
                    "time_constant_s": float(T[i]),
                }
            )
        return out

    def _for_storage(self, storage) -> Simulator:
        """This simulator, or for a fleet of WECC batteries (`StorageFleet.model` "wecc")
        the simulator of the case with them (`stabctl.storage.devices.battery_case`, same
        operating point: the batteries start idle), built once per fleet layout (bus,
        rating, energy and initial charge of each device, the battery fields; the
        MODELS_KEPT most recently used kept)."""
        if storage is not None and not isinstance(storage, st.StorageFleet):
            raise WrongTypeError(
                "run(storage): a StorageFleet is needed (stabctl.uniform_fleet(case, 5)), got "
                f"{type(storage).__name__}"
            )
        if storage is None or storage.model != "wecc" or self.battery_rows is not None:
            return self
        key = (
            tuple((d.bus, d.pmax_mw, d.energy_mj, d.soc0) for d in storage.devices),
            tuple(sorted(storage.battery.items())),
        )
        return self._battery_sims.get(key, lambda: self._battery_simulator(storage))

    def _battery_simulator(self, storage) -> Simulator:
        case, rows = st.battery_case(self.case, storage)
        sim = Simulator(
            case,
            self.op,
            conventions=self.conventions,
            step=self.default_h,
            background_compile=False,
            off_equilibrium=self.off_equilibrium,
            subintervals=self.subintervals,
        )
        sim.battery_rows = rows
        return sim

    def _prepare(self, events, t_end, h, storage, semantics, method="heun", bus_rows=None):
        """Validate, choose the model (storage buses kept), pack the devices, build the
        event grid and the network of every interval (the step checked against the
        fastest time constant for Heun only: the trapezoid is A-stable; the step count
        against the recording of the buses bus_rows, `voltage_rows`, None: every bus)."""
        if semantics not in ("pst", "exact"):
            raise InputError(f"semantics must be 'pst' or 'exact', got {semantics!r}")
        if isinstance(t_end, bool) or not (isinstance(t_end, Real) and math.isfinite(t_end)):
            raise InputError(f"run(t_end): a finite time in s is needed, got {t_end!r}")
        events = require_items(events, "run(events)", "a list of events (Fault, LineTrip, ...)")
        ev_.validate(self.case, events, t_end)
        ev_.warn_unfinished(events, t_end)
        h = self.default_h if h is None else require_number(h, "run(h)", "s")
        m = self.model_for(storage.buses if storage is not None else ())
        xslot = None
        if self.battery_rows is not None:
            start = m.layout.blocks["ibr"][0].start
            xslot = start + int(conv.PLANT_PREF_SLOT) * m.cp.n + self.battery_rows
        sa = st.pack(storage, self.case, m.nc_idx, xslot)
        check_step(self.fastest, h, explicit=method == "heun", freq_hz=self.case.freq_hz)
        n_buses = None if bus_rows is None else bus_rows.size
        check_step_count(t_end, h, self.case, n_buses)
        starts, configs = ev_.stages(self.case, events, t_end, self.op.V)
        nets = [m.network(c) for c in configs]
        if method == "heun":
            check_heun_growth(self.case, np.abs(np.diagonal(nets[0].Y11)), h, t_end)
        pstess = self.conventions == "pstess"  # PSTess's grid, bit for bit
        h_max = None if pstess else [h / self.stiff_substeps(m, net) for net in nets]
        grid = time_grid(starts, t_end, h, pstess, h_max)
        if h_max is not None and min(h_max) < h:
            check_step_count(t_end, h, self.case, n_buses, n_steps=grid.t.size - 1)
        return m, sa, grid, nets

    def stiff_substeps(self, m: DynamicModel, net) -> int:
        """The steps each step of an interval of network `net` is cut into in runs of
        model m: 1 unless a machine's subtransient time constant there is shorter than
        this simulator's step (`default_h`; `stabctl.dynamics.grid.stiff_step`: a fault at
        the terminal of a machine with a tiny x"d), whatever the integrator (the
        trapezoid rings on such a mode).  The count is the nominal step's, so that a run
        at half the step (the half-step check of a verdict or a CCT) halves these steps
        too and shows their error.

        Parameters
        ----------
        m : DynamicModel
            One of this simulator's models (`model_for`).
        net : ReducedNetwork
            The interval's network.

        Returns
        -------
        int
        """
        h = self.default_h
        if m.short_circuit_time_constants.min(initial=np.inf) >= h / STIFF_STEP_PER_TIME_CONSTANT:
            return 1  # no network makes one shorter: most cases, every run
        bound = stiff_step(m.subtransient_time_constants(net, h / STIFF_STEP_PER_TIME_CONSTANT))
        return 1 if bound >= h else int(np.ceil(h / bound - 1e-9))

    def exciter_hmax(self, m: DynamicModel, step: float) -> np.ndarray:
        """The longest sub-step of each exciter of model m in Heun runs of nominal step
        `step` (`stabctl.dynamics.subinterval.exciter_hmax`), all inf (none sub-stepped)
        without sub-intervals.

        Parameters
        ----------
        m : DynamicModel
            One of this simulator's models (`model_for`).
        step : float
            The run's nominal step, s.

        Returns
        -------
        ndarray, shape (n_exc,)
        """
        if not self.subintervals:
            return np.full(m.ep.n, np.inf)
        return exciter_hmax(m.inner_loops, step)

    def sub_stepped(self, step: float, method: str = "heun") -> int:
        """How many exciters Heun runs of nominal step `step` (s) integrate in
        sub-intervals (`exciter_hmax`); 0 for the trapezoid (`method`), which has none.

        Parameters
        ----------
        step : float
            The run's nominal step, s.
        method : {"heun", "trapezoid"}, optional
            The run's integrator; default "heun".

        Returns
        -------
        int
        """
        if method != "heun":
            return 0
        return int(np.isfinite(self.exciter_hmax(self.model, step)).sum())

    def partitions(self, m: DynamicModel, grid, nets) -> tuple[Partition, ...]:
        """The machines' islands stage by stage in a run of model m
        (`stabctl.dynamics.partition.stage_partitions`): empty when no stage trips a
        machine or splits an island.

        Parameters
        ----------
        m : DynamicModel
            One of this simulator's models (`model_for`).
        grid : TimeGrid
            The run's grid (its interval start times).
        nets : sequence of ReducedNetwork
            The network of each interval.

        Returns
        -------
        tuple of Partition
        """
        return stage_partitions(
            grid.starts,
            [n.machine_island for n in nets],
            [n.bus_island for n in nets],
            self.island,
            m.mp.H,
            self.case.machines.mva,
            self.case.buses.pload,
            [n.faulted for n in nets],
        )

    def check_separation_limit(
        self, limit: float, name: str = "separation limit (separation_limit)"
    ) -> None:
        """Refuse a loss-of-synchronism limit not above every machine's angle from its
        island's COI at the power-flow point: every run would report the separation of
        that machine at t = 0, whatever its disturbance.

        Parameters
        ----------
        limit : float
            The separation limit, rad (`run`'s ``separation_limit``).
        name : str, optional
            What the limit is called in the message (the CLI's ``--separation-limit``).

        Raises
        ------
        InputError
            A limit not in (0, MAX_SEPARATION_LIMIT_RAD] (``separation_limit=180``, degrees
            meant, called a run stable whose machines had slipped 87 rad); naming the
            limit and the machine farthest from the COI at the start, with its angle.
        """
        require_number(limit, name, "rad")
        if not 0 < limit <= MAX_SEPARATION_LIMIT_RAD:
            raise InputError(
                f"{name} must be in (0, {MAX_SEPARATION_LIMIT_RAD:g}] rad, got {limit:g} "
                "(in rad: pi, not 180)"
            )
        widest = self._widest_start
        if widest is not None and not limit > widest[1]:
            i, dev = widest
            machine = self.case.machine_name(self.case.machines.number[i])
            raise InputError(
                f"{name} {limit:g} rad is not above the angle of {machine} from the "
                f"centre of inertia at the start, {dev:.4g} rad (before any "
                "disturbance): every run would lose synchronism at t = 0; give a limit "
                f"above {dev:.4g} rad (default pi)"
            )

    @functools.cached_property
    def _widest_start(self) -> tuple[int, float] | None:
        """The machine farthest from its island's COI at the power-flow point and that
        angle, rad (`check_separation_limit`, asked before every run: taken once); None
        without machines."""
        angle = self.model.x0[: self.model.mp.n]
        dev = np.abs(angle - coi_of_islands(angle, self.inertia, self.island))
        if not dev.size:
            return None
        i = int(np.argmax(dev))
        return i, float(dev[i])

    def _semantics(self, semantics: str | None) -> str:
        if semantics is None:
            return "pst" if self.conventions == "pstess" else "exact"
        return semantics

    def run_commanded(
        self,
        events,
        t_end: float,
        storage,
        frames: CommandFrames,
        h: float | None = None,
        semantics: str | None = None,
        separation_limit: float = np.pi,
        stop_at_separation: bool = False,
    ) -> SimulationResult:
        """Simulate with storage devices commanded from measurements (estimator in the loop).

        At each frame time t_f (s, increasing; ``frames.times``) the run is advanced to the
        first grid point at or after t_f and ``frames.decide(t_f, partial)`` is called with
        the recent trajectory (a SimulationResult of the last ``frames.history_s`` seconds
        up to that grid point, so a measurement at t_f can be interpolated; no verdict); it
        returns the device set-points, which take effect at exactly t_f +
        ``frames.latency`` (the step is split there) and hold until the next ones.
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
        frames : CommandFrames
            The frame arrival times (s; those after `t_end` are ignored), the `decide`
            callback, the latency (s) and the history length handed to `decide` (s).
        h : float or None, optional
            Integration step, s, as `run`.
        semantics : {"pst", "exact"} or None, optional
            Event semantics, as `run`.
        separation_limit : float, optional
            Loss-of-synchronism limit, rad, as `run`; default pi.
        stop_at_separation : bool, optional
            End the run at separation, as `run`; default False.

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
        self.check_separation_limit(separation_limit)
        sim = self._for_storage(storage)
        if sim is not self:
            return sim.run_commanded(
                events, t_end, storage, frames, h, semantics, separation_limit, stop_at_separation
            )
        frame_times, latency = np.asarray(frames.times, float), frames.latency
        if np.any(np.diff(frame_times) <= 0) or latency < 0:
            raise InputError("frame times must increase and the latency must be >= 0")
        semantics = self._semantics(semantics)
        prepared = self._prepare(events, t_end, h, storage, semantics)
        grid, pst = prepared[2], semantics == "pst"
        run = _Run(
            self, *prepared, pst, separation_limit, stop_at_separation, n_commands=frame_times.size
        )
        for i, t_f in enumerate(frame_times[frame_times <= t_end]):
            k = int(np.searchsorted(grid.t, t_f - 1e-12))
            run.advance(k)
            if run.status != ig.OK:
                break
            run.command(
                i,
                t_f + latency,
                np.asarray(frames.decide(float(t_f), run.partial(k, frames.history_s)), float),
            )
        else:
            run.advance(grid.t.size - 1)
        return run.finish(storage)

    def _result(
        self, t, rec: ig.Recording, n, wall, limit, bus_rows=None, partitions=()
    ) -> SimulationResult:
        c = self.case
        angle = rec.angle[:n]
        if partitions:
            dev = np.abs(judged_relative(angle, t[:n], self.inertia, self.island, partitions))
        else:
            dev = np.abs(angle - coi_of_islands(angle, self.inertia, self.island))
        lost = np.nonzero(dev.max(axis=1) > limit)[0]
        t_sep, separated = None, []
        if lost.size:
            k = int(lost[0])
            t_sep = float(t[k])
            if partitions:
                now = partitions[int(stage_at(t[k : k + 1], partitions)[0])]
                group = judged_group(angle[k], now)
            else:
                group = separated_group(angle[k], self.inertia, self.island)
            separated = [int(x) for x in c.machines.number[group]]
        return SimulationResult(
            t=t[:n].copy(),
            machines=c.machines.number.astype(int),
            buses=recorded_buses(c, bus_rows)[: rec.V.shape[1]],
            speed=rec.speed[:n],
            angle=angle,
            pelect=rec.pelect[:n],
            qelect=rec.qelect[:n],
            pmech=rec.pmech[:n],
            efd=rec.efd[:n],
            vmag=np.abs(rec.V[:n]),
            vang=np.angle(rec.V[:n]),
            inertia=self.inertia,
            island=self.island,
            converters=c.converters.number.astype(int),
            ibr_p=rec.S_ibr[:n].real.copy() if len(c.converters) else None,
            ibr_q=rec.S_ibr[:n].imag.copy() if len(c.converters) else None,
            stable=t_sep is None and de_energised_at(partitions, float(t[n - 1])) is None,
            t_separation=t_sep,
            separated=separated,
            partitions=partitions,
            meta={
                "case": c.name,
                "conventions": self.conventions,
                "wall_time_s": wall,
                "max_initial_derivative": self.model.initial_residual[0],
                "max_initial_derivative_state": self.model.initial_residual[1],
            },
        )


#: simulated time between two calls of a run's monitor (`Simulator.run`), s
MONITOR_EVERY_S = 0.1

#: wall time between two pauses of a run's compiled loop (`_Run.advance`), s: signals
#: are handled and progress shown there
PAUSE_EVERY_S = 0.25
#: steps of a run's first piece while its simulator has measured none
FIRST_PIECE_STEPS = 32


class Pieces:
    """How many steps a run's compiled loop takes before it pauses (`_Run.advance`):
    about PAUSE_EVERY_S of wall time at the cost per step of the last piece of this
    simulator's runs (FIRST_PIECE_STEPS before one was measured).  A short run then takes
    one piece: a CCT search's thousands of runs pay nothing for the pauses."""

    def __init__(self) -> None:
        self.per_step: float | None = None

    def steps(self) -> int:
        """Steps of the next piece (>= 1)."""
        if self.per_step is None:
            return FIRST_PIECE_STEPS
        return max(1, int(PAUSE_EVERY_S / max(self.per_step, 1e-9)))

    def took(self, wall: float, steps: int) -> None:
        """A piece of `steps` steps took `wall` s.  A piece of fewer than 8 steps (the
        end of a run) says little of the cost per step, its call's own cost included:
        kept only when it is the first measure or lowers the last (a first piece slowed
        by loading the compiled code then does not hold the pieces to single steps)."""
        if steps < 1:
            return
        per_step = wall / steps
        if steps >= 8 or self.per_step is None or per_step < self.per_step:
            self.per_step = per_step


def _advance_monitored(run: _Run, monitor) -> str | None:
    """Advance `run` to its end in pieces of MONITOR_EVERY_S, calling `monitor` with the
    trajectory so far after each; returns its first verdict (the run stops there) or None
    (the run went to its end or stopped by itself).  Pausing does not change the
    trajectory (`integrate` continues from its carry)."""
    t, last = run.grid.t, run.grid.t.size - 1
    while run.k < last and run.status == ig.OK:
        k1 = min(int(np.searchsorted(t, t[run.k] + MONITOR_EVERY_S - 1e-12)), last)
        run.advance(max(k1, run.k + 1))
        if run.status != ig.OK:
            return None
        verdict = monitor(run.partial(run.k, np.inf, voltages=False))
        if isinstance(verdict, str):
            return verdict
        if verdict is not None:
            raise WrongTypeError(
                "run(monitor): a monitor returns None (run on) or a string (stop here, its "
                f"early verdict), got {verdict!r} ({type(verdict).__name__})"
            )
    return None


def islanding_log(grid, nets, case: Case | None = None, partitions=()) -> list[dict]:
    """The buses each stage of a run newly cuts from every machine (de-energised, their
    load shed: PSS/E's islanding, `stabctl.dynamics.model.Model.network`), and the islands
    with machines it newly cuts off the main grid (their machines lost,
    `stabctl.dynamics.partition`).

    Parameters
    ----------
    grid : TimeGrid
        The run's grid (its interval start times).
    nets : sequence of ReducedNetwork
        The network of each interval.
    case : Case or None, optional
        The case run (its bus and machine numbers); needed with `partitions`.
    partitions : sequence of Partition, optional
        The run's partitions (`Simulator.partitions`); default none.

    Returns
    -------
    list of dict
        In stage order, per stage first the buses cut from every machine: ``t_s`` (its
        start, s), ``buses`` (numbers), ``load_shed_pu`` (P and Q shed, [P, Q] pu on the
        system base); then one per island apart from the main grid: ``t_s``, ``buses``
        (the island's) and ``machines`` (its machine numbers).  Empty when no stage
        islands a bus.
    """
    out, seen = [], set()
    for start, net in zip(grid.starts, nets):
        new = [(b, S) for b, S in net.islanded if b not in seen]
        if new:
            shed = sum(S for _, S in new)
            out.append(
                {
                    "t_s": float(start),
                    "buses": [b for b, _ in new],
                    "load_shed_pu": [float(shed.real), float(shed.imag)],
                }
            )
        seen = {b for b, _ in net.islanded}
    if partitions and case is not None:
        out += machine_islands_log(
            partitions,
            [n.bus_island for n in nets],
            case.bus_indices(case.machines.bus),
            case.buses.number.astype(int),
            case.machines.number.astype(int),
        )
        out.sort(key=lambda entry: entry["t_s"])  # stable: a stage's dead buses first
    return out


def _held_at_q_limits(case: Case, held: np.ndarray, settings: dict) -> str:
    """What to add to a refusal of `case`'s start when its power flow held the PV buses
    `held` (bus numbers) at their Q limits and a simulator of the power flow without Q
    limits (as ANDES solves it, pv2pq = 0) starts: their numbers and the option; '' when
    none was held or that start is refused too (then the Q limits are not the cause).

    Parameters
    ----------
    case : Case
        The case as given to the simulator.
    held : numpy.ndarray
        Bus numbers the power flow held at a Q limit.
    settings : dict
        The simulator's other arguments (`Simulator`).

    Returns
    -------
    str
        ``"; the power flow held bus 3 at its Q limit ..."`` or ''.
    """
    if not held.size:
        return ""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # said by the first try already
            Simulator(case, q_limits=False, background_compile=False, **settings)
    except StabctlError:
        return ""
    listed = ", ".join(map(str, held[:10])) + (
        f" and {held.size - 10} more" if held.size > 10 else ""
    )
    one = held.size == 1
    return (
        f"; the power flow held bus{'' if one else 'es'} {listed} at "
        f"{'its Q limit' if one else 'their Q limits'}, and without Q limits the case starts "
        f"at rest: {advice('q_limits=False', '--no-q-limits')} solves the power flow as "
        "ANDES does (pv2pq = 0, the power flow import-andes compares with)"
    )


def _named_converter(case: Case, err: CaseError) -> CaseError:
    """`err` as it is, or, when it is a converter's (``ibr_con`` row r: one that cannot
    start at its power-flow point), with the converter named as outputs name it
    (``C3 (bus 7)``, the ``pibr_pu.C3`` columns) before its table row."""
    row, table = getattr(err, "row", None), getattr(err, "table", None)
    said = str(err)
    head = f"ibr_con row {row + 1}: " if row is not None else ""
    if table != "ibr_con" or not said.startswith(head) or row >= len(case.converters):
        return err
    conv = case.converters
    who = f"converter C{int(conv.number[row])} (bus {int(conv.bus[row])}, ibr_con row {row + 1})"
    return CaseError(f"{who}: {said[len(head) :]}", table=table, row=row)


#: the controls outside their limits a refusal names (`_named_limits`); the rest counted
NAMED_LIMITS = 5


def _named_limits(case: Case, err: InitialLimitError) -> InitialLimitError:
    """`err` with each control named by its machine or bus instead of its table row
    (`stabctl.dynamics.infeasible.offenders`), and what to do: a run must start at rest."""
    lines = offenders(case, err)
    todo = advice(
        "leave_out_infeasible(case) leaves such controls out, named; "
        "Simulator(suspect_starts='run') runs on as PSS/E does",
        "the import's --leave-out-infeasible leaves such controls out, named; simulate "
        "--suspect-starts run runs on as PSS/E does",
    )
    named = InitialLimitError(err.table, err.rows, lines)
    shown = "; ".join(f"the {line}" for line in lines[:NAMED_LIMITS])
    more = f"; and {len(lines) - NAMED_LIMITS} more" if len(lines) > NAMED_LIMITS else ""
    named.args = (f"{shown}{more}: the run cannot start at rest ({todo})",)
    return named


def _with_solved_taps(case: Case, taps: np.ndarray) -> Case:
    """The case with the on-load taps its power flow moved (PST's drivers run the dynamics
    on ``bus_sol`` and the line matrix with ``lftap``'s final taps); the case itself when
    none moved.  Without them a case whose taps move (Kundur at 110 % load: 0.975 ->
    0.96875, 0.9688 -> 0.9563) started off equilibrium, its network not the power
    flow's (0.566 on exc.VTR.G4).

    Parameters
    ----------
    case : Case
        The case whose power flow was solved.
    taps : numpy.ndarray
        The power flow's final tap ratios, shape (n_branches,)
        (`stabctl.network.powerflow.PowerFlowResult.taps`).

    Returns
    -------
    Case
        ``case``, or a copy with ``branches.tap`` replaced.
    """
    given = np.where(case.branches.tap == 0, 1.0, case.branches.tap)
    if np.array_equal(given, taps):
        return case
    return case.replace(branches=case.branches.replace(tap=np.asarray(taps, float)))


def _with_solved_shunts(case: Case, levels: np.ndarray) -> Case:
    """The case with its switched shunts at the levels its power flow stepped them to (their
    b0, g0 those levels' values: `stabctl.network.switched_shunts`); the case itself
    without switched shunts.  A run holds them there (docs/pst_models.md 15).

    Parameters
    ----------
    case : Case
        The case whose power flow was solved.
    levels : numpy.ndarray
        The power flow's levels, int (n_switched,)
        (`stabctl.network.powerflow.PowerFlowResult.shunt_levels`).

    Returns
    -------
    Case
        ``case``, or a copy with ``switched_shunts.b0``, ``g0`` replaced.
    """
    t = case.switched_shunts
    if not len(t):
        return case
    y = sws.admittances(t, levels)
    return case.replace(switched_shunts=t.replace(b0=y.imag, g0=y.real))


def _check_method(method: str, semantics: str, storage) -> None:
    """Refuse an unknown method, and the trapezoid with what it does not implement."""
    if method not in ("heun", "trapezoid"):
        raise InputError(f"method must be 'heun' or 'trapezoid', got {method!r}")
    if method == "trapezoid" and semantics != "exact":
        raise InputError(
            f"method 'trapezoid' takes the 'exact' event semantics only, got {semantics!r} "
            "(the pstess conventions' default): give semantics='exact' or method 'heun'"
        )
    if method == "trapezoid" and storage is not None:
        raise InputError(
            "method 'trapezoid' takes no storage devices (their switching instants are"
            " located inside Heun's steps): use method 'heun'"
        )


def simulator_cached() -> bool:
    """Whether the simulator's kernels, the integrator
    (`stabctl.dynamics.integrator.integrate`) and the model's evaluation
    (`stabctl.dynamics.model.evaluate_kernel`), are in the on-disk cache
    (`stabctl._jit.cache.cached`): a new process loads them instead of compiling them."""
    return cached(ig.integrate) and cached(evaluate_kernel)


class _Run:
    """One simulation in progress: the compiled loop advanced piecewise (see `integrate`)."""

    def __init__(
        self, sim: Simulator, m, sa, grid, nets, pst, limit, stop, n_commands=0, bus_rows=None
    ):
        self.sim, self.m, self.sa, self.grid = sim, m, sa, grid
        n_nc = m.V_nc0.size
        #: the buses whose voltages the run records (`voltage_rows`: None, every bus)
        self.bus_rows = bus_rows
        n_bus = sim.case.n_bus if bus_rows is None else bus_rows.size
        self.rec = ig.recording(grid.t.size, m.mp.n, n_bus, sa.pmax.size, m.cp.n)
        self.carry = ig.Carry(
            x=m.x0.copy(),
            kept=KeptBuses(
                V=m.V_nc0.copy(),
                held=np.zeros(n_nc, np.bool_),  # loads held low
                S_extra=np.zeros(n_nc, np.complex128),
            ),
            held_stage=np.full(1, -1),
            devices=device_state(sa, n_commands),
            health=ig.Health(np.zeros(grid.t.size), *(np.zeros(1, np.int64) for _ in range(3))),
        )
        self.nets, self.steps = sim._stacked_stages(nets, bus_rows), ig.step_grid(grid)
        #: the stages' networks (`stabctl.dynamics.prefix` tells a run's pre-event one by it)
        self.nets_list = nets
        #: the machines' islands stage by stage when a stage trips a machine or splits an
        #: island (`Simulator.partitions`), else empty
        self.partitions = sim.partitions(m, grid, nets)
        #: each stage's islands, COI weights and judged machines for the compiled loop (its
        #: devices' relative speeds and its stop at separation)
        self.opts = ig.run_options(
            pst, sim.inertia, sim.island, self.partitions, len(nets), limit, stop
        )
        self.limit = limit
        #: the model's parameters with the limiters' reach (`stabctl.dynamics.prefix.reach`)
        self.params = m.params._replace(
            reach=reach(grid.h, grid.step), exc_hmax=sim.exciter_hmax(m, grid.step)
        )
        self.k, self.status, self.wall, self.stored = 0, ig.OK, 0.0, False
        self.evaluate: int | None = None
        #: the steps of each call of the compiled loop (`Pieces`: the simulator's, so
        #: that a search's short runs start from the cost its earlier runs measured)
        self.pieces = sim._pieces

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
        advance(0) at the start stores the initial point.

        The compiled loop runs in pieces of about PAUSE_EVERY_S of wall time (`pieces`),
        so that Python's signal handlers run between them (Ctrl-C, SIGTERM: within a
        second, not at the end of a long run) and a run shown (`stabctl.progress.
        run_progress`) says how far it is; pausing leaves the trajectory as it is
        (`integrate` continues from its carry)."""
        if self.status != ig.OK or k1 < self.k or (k1 == self.k and self.stored):
            return
        self.stored = True
        if self.evaluate is None:  # the model's evaluation: compiled or loaded here
            self.evaluate = evaluate_address(self.params)
        await_background(ig.integrate)
        shown = run_progress(float(self.grid.t[self.k]), float(self.grid.t[-1]))
        try:
            while True:
                k = self.k
                k_next = min(k1, k + self.pieces.steps())
                wall = time.perf_counter()
                self.status, self.k = ig.integrate(*self.arguments(k_next))
                spent = time.perf_counter() - wall
                self.wall += spent
                self.pieces.took(spent, self.k - k)
                if shown is not None:
                    shown(float(self.grid.t[self.k]))
                if self.status != ig.OK or self.k >= k1:
                    return
        finally:
            if shown is not None:
                shown.close()

    def arguments(self, k1: int) -> tuple:
        """The arguments of `integrate` from the last stored grid index to k1 (an address
        of 0 before the first `advance`)."""
        return (
            self.carry,
            self.k,
            k1,
            self.steps,
            self.nets,
            self.params,
            self.sa,
            self.opts,
            self.rec,
            self.evaluate or 0,
        )

    def command(self, i: int, t_apply: float, modes) -> None:
        """Schedule command i: device set-points (units of each rating) from t_apply (s)."""
        ds = self.carry.devices
        ds.cmd_t[i], ds.cmd_mode[i] = t_apply, modes

    def partial(self, k: int, history_s: float, voltages: bool = True) -> SimulationResult:
        """The trajectory of the last `history_s` seconds up to grid index k (views, no
        verdict): a callback at every frame then costs the same late in a long run as
        early (the whole trajectory would make a run's cost grow with its length squared).
        Without `voltages`, vmag and vang are empty (n_t, 0) (a monitor of the machines
        only, `Simulator.run`, is spared their computation)."""
        r, c, n = self.rec, self.sim.case, k + 1
        lo = max(int(np.searchsorted(self.grid.t[:n], self.grid.t[k] - history_s)) - 1, 0)
        V = r.V[lo:n] if voltages else np.zeros((n - lo, 0))
        return SimulationResult(
            t=self.grid.t[lo:n],
            machines=c.machines.number.astype(int),
            buses=recorded_buses(c, self.bus_rows)[: V.shape[1]],
            speed=r.speed[lo:n],
            angle=r.angle[lo:n],
            pelect=r.pelect[lo:n],
            qelect=r.qelect[lo:n],
            pmech=r.pmech[lo:n],
            efd=r.efd[lo:n],
            vmag=np.abs(V),
            vang=np.angle(V),
            inertia=self.sim.inertia,
            island=self.sim.island,
            devices=np.arange(1, self.sa.pmax.size + 1),
            pesd=self.rec.P[lo:n],
            partitions=self.partitions,
        )

    def _end_voltages(self) -> np.ndarray | None:
        """Every bus's |V| (n_bus,) pu at the last stored point, from one evaluation of
        the model there: a run that records no voltage (a CCT search's) still tells
        where it ends (`SimulationResult.end_state`); None when the network has no
        solution there."""
        kept = self.carry.kept
        net = self.nets_list[int(self.grid.interval[self.k])]
        try:
            _, out = self.m.evaluate(self.carry.x.copy(), net, kept.V.copy(), kept.S_extra.copy())
        except SimulationError:
            return None
        return np.abs(out.V_bus)

    def finish(self, storage) -> SimulationResult:
        """The result; raises SimulationError (with the partial result) after a divergence."""
        sim, g, k_end = self.sim, self.grid, self.k
        res = sim._result(
            g.t, self.rec, k_end + 1, self.wall, self.limit, self.bus_rows, self.partitions
        )
        recorded = self.bus_rows is None or self.bus_rows.size
        if res.stable and self.status == ig.OK and not recorded:  # `end_state` still told
            res.meta["end_vmag"] = self._end_voltages()
            res.meta["end_buses"] = self.sim.case.buses.number.astype(int)
        if storage is not None:
            log = self.rec.log
            log = log[~np.isnan(log[:, 0])]
            _attach_storage(
                res,
                storage,
                self.rec.P[: k_end + 1],
                self.rec.stats,
                sim.case.base_mva,
                log,
                sim.case.freq_hz,
                sim.battery_rows,
            )
        t_fail = g.t[min(k_end + 1, g.t.size - 1)]
        if self.status == ig.UNSTABLE_STEP:
            q, x = int(self.carry.health.bad[0]), self.carry.x
            if res.ran_away(sim.case, q, float(x[q]), float(t_fail)):
                return res  # a verdict: the separated machine's runaway ends the run
            raise NumericalInstabilityError(
                f"case '{sim.case.name}': numerical instability in the step ending at t = "
                f"{t_fail:.4f} s: state {self.m.state_name(q)} = {x[q]:.6g} "
                f"({ig.symptom(x[q], q, self.m.mp.n)}); the step h = "
                f"{g.h[g.interval[k_end]]:.6g} s is too large for this model: use a smaller "
                f"step (the run reached {g.t[k_end]:.4f} s)",
                result=res,
            )
        if self.status < 0:
            stage = g.interval[min(k_end + 1, g.t.size - 1)]
            raise SimulationError(
                f"case '{sim.case.name}': the network/load equations did "
                f"not converge (voltage collapse) in the step ending at "
                f"t = {t_fail:.4f} s (the run reached "
                f"{g.t[k_end]:.4f} s){no_solution_hint(sim.case, self.nets_list[stage])}",
                result=res,
            )
        return res


class RunHandle:
    """A Heun run its caller advances in pieces (`Simulator.start`): paused anywhere, it
    continues bit for bit (`_Run.advance`), its quiet start copied from the simulator's
    prefixes as `Simulator.run`'s (`stabctl.dynamics.prefix`) unless its fleet takes
    commands.

    Parameters
    ----------
    run : _Run
        The run, not advanced yet.
    storage : StorageFleet or None
        Its fleet (for the result's device figures).

    Attributes
    ----------
    run : _Run
        The run (its grid ``run.grid``, last grid index ``run.k``).
    """

    def __init__(self, run: _Run, storage) -> None:
        self.run, self._storage = run, storage

    @property
    def done(self) -> bool:
        """Whether the run is over: at its end, stopped (separation) or failed."""
        return self.run.status != ig.OK or self.run.k >= self.run.grid.t.size - 1

    def advance_to(self, t: float) -> None:
        """Integrate up to the first grid point at or after `t` (the run's end at most);
        nothing after a stop.

        Parameters
        ----------
        t : float
            Time, s (absolute run time).
        """
        run = self.run
        k1 = min(int(np.searchsorted(run.grid.t, t - 1e-12)), run.grid.t.size - 1)
        if run.k == 0 and not run.stored and run.sa.kind != law.EXTERNAL:
            integrate_from_cache(run, run.sim._prefixes, k1)
        else:
            run.advance(k1)

    def result(self) -> SimulationResult:
        """The result up to the last grid point reached (`Simulator.run`'s when at the
        end), with its verdict on that stretch; the run can go on after it.

        Returns
        -------
        SimulationResult
            As `Simulator.run`'s (its arrays views of the recording, which later pieces
            do not rewrite).

        Raises
        ------
        NumericalInstabilityError, SimulationError
            The run diverged (as `Simulator.run`, with the partial result).
        """
        run = self.run
        return run.sim._annotated(
            run.finish(self._storage), run.grid, run.nets_list, run.partitions
        )


#: Two switchings of a device closer than this (s) count as chattering.
CHATTER_S = 0.02


def _attach_storage(
    res: SimulationResult, fleet, P, stats, base_mva, log, f0, battery_rows=None
) -> None:
    """Device powers and per-device figures: switchings, chattering (switchings within
    CHATTER_S of the previous one), energy absorbed and delivered (MJ), highest and lowest
    stored energy relative to the start (MJ, exact at located switchings:
    `stabctl.dynamics.switching.account`), all of the power the network takes (`pesd`),
    peak power actually used (MW), seconds commanded and of those with no power taken
    (`_commanded_seconds`); the switching log (time s, device number, new mode,
    relative speed Hz) in res.meta["switchings"].  WECC batteries (their converter rows
    `battery_rows`): the power is the converter's (its P injection, sign changed), the
    energy figures its integral on the time grid (`energy_excursion`), the law's
    power in res.meta["pesd_command"]."""
    res.devices = np.arange(1, len(fleet.devices) + 1)
    if battery_rows is not None:
        res.meta["pesd_command"] = P
        P = -res.ibr_p[:, battery_rows]
        stats = stats.copy()
        for i in range(P.shape[1]):
            ex = st.energy_excursion(res.t, P[:, i])
            stats[i, 1:] = [
                ex["absorbed_mj"],
                ex["delivered_mj"],
                ex["soc_high_mj"],
                ex["soc_low_mj"],
            ]
    res.pesd = P
    res.meta["switchings"] = [(float(t), int(d) + 1, int(m), float(r * f0)) for t, d, m, r in log]
    res.meta["storage"] = [
        {
            "device": i + 1,
            "bus": d.bus,
            "machine": d.machine,
            "pmax_mw": d.pmax_mw,
            "switchings": int(stats[i, 0]),
            "chattering": int(np.sum(np.diff(log[log[:, 1] == i, 0]) < CHATTER_S)),
            "energy_absorbed_mj": float(stats[i, 1] * base_mva),
            "energy_delivered_mj": float(stats[i, 2] * base_mva),
            "soc_high_mj": float(stats[i, 3] * base_mva),
            "soc_low_mj": float(stats[i, 4] * base_mva),
            "peak_power_mw": float(np.abs(P[:, i]).max() * base_mva) if P.size else 0.0,
            **_commanded_seconds(res.t, P[:, i], log[log[:, 1] == i]),
        }
        for i, d in enumerate(fleet.devices)
    ]


def _commanded_seconds(t: np.ndarray, p: np.ndarray, log: np.ndarray) -> dict:
    """How long a device was commanded (its mode not 0, from its rows of the switching
    log, (n, 4): t, device, mode, relative speed) and how long of that the network took
    none of its power ``p`` (n_t,): its bus below PST's 0.5 pu low-voltage switch or its
    energy at a limit (`stabctl.dynamics.switching.delivered`; round 45: a 3000 MW device
    beside a 900 MVA machine switched 4 times and moved nothing, without a word).  Over
    the time grid's intervals whose both ends are so, s."""
    if not t.size or not log.size:
        return {"commanded_s": 0.0, "commanded_idle_s": 0.0}
    k = np.searchsorted(log[:, 0], t, side="right") - 1
    on = np.where(k >= 0, log[np.maximum(k, 0), 2], 0.0) != 0
    idle = on & (p == 0.0)
    dt = np.diff(t)
    return {
        "commanded_s": float(dt[on[:-1] & on[1:]].sum()),
        "commanded_idle_s": float(dt[idle[:-1] & idle[1:]].sum()),
    }


def separated_group(
    delta: np.ndarray, inertia: np.ndarray, island: np.ndarray | None = None
) -> np.ndarray:
    """Machines that lost synchronism: split the rotor angles at their largest gap into two
    coherent groups and return the indices of the group with the smaller inertia (the
    leading group on a tie), sorted.  With islands (n_mac,) int, within the island of the
    machine farthest from its island's COI."""
    within = np.arange(delta.size)
    if island is not None and np.max(island) > 0:
        far = np.argmax(np.abs(delta - coi_of_islands(delta, inertia, island)))
        within = np.flatnonzero(island == island[far])
    order = within[np.argsort(delta[within])]
    if order.size < 2:  # a machine alone: no gap to split at
        return np.sort(order)
    cut = int(np.argmax(np.diff(delta[order]))) + 1
    lagging, leading = order[:cut], order[cut:]
    m_lag, m_lead = inertia[lagging].sum(), inertia[leading].sum()
    group = leading if m_lead <= m_lag * (1 + 1e-9) else lagging
    return np.sort(group)


def judged_group(delta: np.ndarray, partition: Partition) -> np.ndarray:
    """The machines that lost synchronism (`separated_group`) among those a partition
    judges (`stabctl.dynamics.partition.Partition`), against its islands.

    Parameters
    ----------
    delta : ndarray, shape (n_mac,)
        Rotor angles, rad.
    partition : Partition
        The machines' islands at that time.

    Returns
    -------
    ndarray of int
        Machine indices (0-based), sorted.
    """
    on = np.flatnonzero(partition.judged)
    return on[separated_group(delta[on], partition.inertia[on], partition.island[on])]


def voltage_rows(case: Case, voltages) -> np.ndarray | None:
    """The buses whose voltages a run records (`Simulator.run`, ``voltages``).

    Parameters
    ----------
    case : Case
        The simulated case.
    voltages : bool or sequence of int
        True: every bus; False: none; else bus numbers (any order, repeats ignored).

    Returns
    -------
    ndarray of int or None
        None for every bus (also when the numbers name them all), else the 0-based bus
        indices in the case's order (possibly none).

    Raises
    ------
    UnknownBusError
        A number that is no bus of the case.
    InputError
        A text (``"13"`` was read as buses 1 and 3).
    """
    if isinstance(voltages, (bool, np.bool_)):
        return None if voltages else np.zeros(0, np.int64)
    buses = bus_numbers(voltages, "run(voltages)", "True, False or bus numbers")
    rows = np.unique([case.bus_index(b) for b in buses]).astype(np.int64)
    return None if rows.size == case.n_bus else rows


def recorded_buses(case: Case, bus_rows) -> np.ndarray:
    """The numbers of the buses a run records (`voltage_rows`), int (n_recorded,)."""
    numbers = case.buses.number.astype(int)
    return numbers if bus_rows is None else numbers[bus_rows]
