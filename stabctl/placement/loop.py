"""ESD placement verified by nonlinear simulation: a trust-region loop around the convex
program of `stabctl.placement.program` (docs/placement.md, section 4).

Every allocation proposed is simulated (`stabctl.placement.evaluation.verify`: the CCT of every
contingency by bisection, in parallel, and its gradient in the ratings from the SIME
margin).  The loop is sequential linear programming with a trust region on an exact
penalty merit (Nocedal, Wright, Numerical Optimization, 2nd ed., 2006, sec. 18.5):

    merit(P) = cost . P + site_cost * sites(P) + mu_t sum_c max(0, target_c - CCT_c(P))
               + mu_d * damping shortfall

1. P = 0 (or a given start, e.g. a uniform fleet known to meet the targets) is simulated;
   each contingency's CCT is linearised there (a cut).
2. The program is solved with the cuts of the current allocation P (elastic at the merit's
   prices), the damping rows (refined at the trial by recomputed eigenvalues until they
   stop improving, `stabctl.smallsignal.damping`), and |P' - P| <= radius; the trial P' is rounded.
3. P' is simulated.  rho = (merit(P) - merit(P')) / (its linearised prediction): if
   rho >= 0.1 P' is accepted and every cut replaced by its linearisation at P' (the
   constraints updated from the new trajectories); the radius doubles when the step was
   good (rho >= 0.75) and reached it; otherwise P stays, the radius becomes half the step
   and the cuts at P are corrected to pass through the CCTs simulated at P' (scaled
   multi-secant, `CCTCut.through`; so are the cuts of an accepted P' through the P it
   came from).
4. Stop when the program predicts less than `rtol` of the current cost as further saving
   (converged if the current allocation meets every target, stuck otherwise), or after
   `max_iter` simulated allocations.
5. Feasibility restoration: the cheapest allocation that missed by at most a few
   tolerances is scaled up by 3, 6 and 10 % and simulated while cheaper than the best
   verified one, the contingencies it missed first (`_restore`).
The cheapest allocation that met every target in simulation is returned.  Whenever the
hard program (no slack) is infeasible, the contingencies it names (`placement.diagnose`)
are simulated with every site at its bound and, when that misses, with only the sites
whose rating raises their linearised CCT at their bound (`bound_allocations`: a device
that lowers a CCT is not forced in); below target at both proves the infeasibility
(`InfeasibleError` naming them).  So are the contingencies a loop that verified nothing
never met at any allocation it simulated, so that each gets a verdict.
"""

from __future__ import annotations

import logging
import threading
import time
from contextlib import nullcontext
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from stabctl.dynamics.options import ModelOptions
from stabctl.errors import InputError, check_fields, require_instance
from stabctl.parallel import RunnerOptions, worker_pool
from stabctl.placement.evaluation import Contingency, Evaluator, VerifyOptions, cuts_from, verify
from stabctl.placement.program import (
    Allocation,
    InfeasibleError,
    candidate_sites,
    solve_allocation,
    sparse_allocation,
    total_mw,
)
from stabctl.stability.cct import SearchOptions, cached_simulator
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import ESD_MODELS

logger = logging.getLogger(__name__)

MIN_MW = 1.0  # ratings below this are not installed (MW)
#: The paper's Table 3 law (`stabctl.storage.devices.BangBangCOI` defaults: 100 mHz deadband, 0.8 pu
#: voltage gate, system COI, no hysteresis).
DEFAULT_CONTROLLER = BangBangCOI()
ACCEPT, GOOD = 0.1, 0.75
#: Feasibility restoration (`_restore`): near miss = CCT shortfall <= RESTORE_MISS
#: tolerances in all; scale factors tried on it, in order.
RESTORE_MISS, RESTORE_SCALE = 3, (1.03, 1.06, 1.1)
#: One linearisation of a shared (cached) simulator at a time: `place` and `evaluations`
#: may run in threads of one process (`stabctl.studies.placement`).
_LINEARISE = threading.Lock()


@dataclass
class PlacementResult:
    """Outcome of `place`.

    allocation: the cheapest verified Allocation (or the last accepted one when none met
    every target); verified: every contingency's simulated CCT reaches its target (and,
    with zeta_min, the recomputed damping); evaluations: contingency name -> evaluation
    (`stabctl.placement.evaluation.evaluate`) at that allocation; base: the same without storage;
    iterations: one dict per allocation simulated; damping: (frequency Hz, damping ratio)
    of the electromechanical modes at the allocation, or None; message: why it stopped;
    solve_times_s: Clarabel's time of every program solved.
    """

    allocation: Allocation
    verified: bool
    evaluations: dict
    base: dict
    iterations: list
    contingencies: tuple
    damping: tuple | None = None
    wall_time_s: float = 0.0
    message: str = ""
    solve_times_s: list = field(default_factory=list)

    def to_dict(self) -> dict:
        """JSON-ready summary (MW, s)."""
        a = self.allocation
        out = {
            "verified": self.verified,
            "message": self.message,
            "allocation": a.rows(),
            "total_mw": a.total_mw,
            "n_sites": a.n_sites,
            "contingencies": [self.row(c) for c in self.contingencies],
            "iterations": self.iterations,
            "wall_time_s": self.wall_time_s,
            "solve_times_s": self.solve_times_s,
        }
        if self.damping is not None:
            out["damping"] = [
                {"freq_hz": float(f), "damping_ratio": float(z)} for f, z in zip(*self.damping)
            ]
        return out

    def row(self, c: Contingency) -> dict:
        """One contingency: target, CCT without and with the allocation (s), met."""
        cct = self.evaluations[c.name]["cct_s"]
        return {
            "name": c.name,
            "fault": c.fault.describe(),
            "target_cct_s": c.target_cct_s,
            "cct_no_storage_s": self.base[c.name]["cct_s"],
            "cct_s": cct,
            "met": c.met_by(cct),
        }


@dataclass(frozen=True)
class Study:
    """What the evaluations and loops of one placement study share.

    Attributes
    ----------
    sites : tuple of Site or None
        Candidate sites (None: `candidate_sites`, every generator's HV bus, up to 50 % of
        its MVA).
    controller : BangBangCOI or None
        The bang-bang law of every ESD (None: `DEFAULT_CONTROLLER`).
    search : SearchOptions
        CCT bisection tolerance and search limit (``tol``, ``t_max``, s).
    model : ModelOptions
        Conventions and step of every run.
    runner : RunnerOptions
        Processes (1: in this process) or the Dask scheduler of the evaluations
        (`stabctl.parallel.worker_pool`), when no run_map is given.
    run_map : callable or None
        A `stabctl.parallel.worker_pool` map kept open by the caller (so that workers and
        their caches serve many calls); None: a pool per call, as `runner` says.
    esd_model : {"ideal", "wecc"}
        The devices' model (`stabctl.storage.devices.StorageFleet.model`): ideal power
        sources or WECC batteries taking the law's power as their plant reference.
    critical_reference : bool
        The law armed per contingency (``place --coi critical``, not the paper's): in
        the runs of each contingency every device takes as reference the COI of the
        other group, the group being the machines the fault separates without storage
        (`stabctl.placement.evaluation.controller_dict`); the controller's own ``coi``
        is then not used.  Default False: the controller as given.
    case_digest : str or None
        The digest of the case as the study first read it, put in every job (a plan's,
        so that its rounds run on one content: `stabctl.stability.cct.job_case`); None:
        the case's as each evaluation reads it.

    Raises
    ------
    WrongTypeError
        search, model, runner or controller not their options (controller: or None),
        critical_reference not a bool.
    InputError
        esd_model not one of `stabctl.storage.devices.ESD_MODELS`.
    """

    sites: tuple | None = None
    controller: BangBangCOI | None = None
    search: SearchOptions = SearchOptions()
    model: ModelOptions = ModelOptions()
    runner: RunnerOptions = RunnerOptions(workers=1)
    run_map: Any = None
    esd_model: str = "ideal"
    critical_reference: bool = False
    case_digest: str | None = None

    def __post_init__(self) -> None:
        check_fields(self)
        for name, kind in (
            ("search", SearchOptions),
            ("model", ModelOptions),
            ("runner", RunnerOptions),
            ("controller", BangBangCOI),
        ):
            require_instance(getattr(self, name), kind, f"Study({name})", none=name == "controller")
        if self.esd_model not in ESD_MODELS:
            raise InputError(
                f"Study(esd_model): one of {', '.join(ESD_MODELS)} is needed, got "
                f"{self.esd_model!r}"
            )

    @property
    def law(self) -> BangBangCOI:
        """The ESDs' law (`DEFAULT_CONTROLLER` when none is given)."""
        return self.controller or DEFAULT_CONTROLLER

    def evaluator(self, run_map, case: str, sites, beta) -> Evaluator:
        """The `Evaluator` of this study's runs.

        Parameters
        ----------
        run_map : callable
            ``run_map(func, jobs) -> results``.
        case : str
            Case name or file.
        sites : tuple of Site
            Candidate sites.
        beta : numpy.ndarray
            Distribution factors, shape (n_mac, n_sites).

        Returns
        -------
        Evaluator
        """
        return Evaluator(
            run_map,
            case,
            sites,
            beta,
            self.law,
            self.search,
            self.model,
            esd_model=self.esd_model,
            critical_reference=self.critical_reference,
            case_digest=self.case_digest or cached_simulator(case, self.model).case.digest(),
        )


@dataclass(frozen=True)
class PlaceOptions:
    """Settings of the verified loop (`place`).

    Attributes
    ----------
    zeta_min : float or None
        Least damping ratio of every electromechanical mode (None: no small-signal
        constraint).
    amplitude_hz : float
        Relative-speed amplitude (Hz) at which the bang-bang law's describing function is
        taken (`stabctl.smallsignal.damping`).
    max_sites : int or None
        At most this many sites (`placement.sparse_allocation`).
    site_cost : float or array_like
        Cost per site used (one number or one per site).
    safety_s : float or None
        CCT margin the program asks above each target (s, default 2 tol).
    max_iter : int
        Allocations simulated at most.
    rtol : float
        Relative saving below which the loop stops once the targets are met.

    Raises
    ------
    WrongTypeError
        A field of another type (`stabctl.errors.check_fields`).
    InputError
        A field out of its range, named: zeta_min outside [0, 1), amplitude_hz <= 0,
        max_sites or max_iter < 1, safety_s < 0, rtol outside [0, 1).
    """

    zeta_min: float | None = None
    amplitude_hz: float = 0.2
    max_sites: int | None = None
    site_cost: Any = 0.0
    safety_s: float | None = None
    max_iter: int = 10
    rtol: float = 0.02

    def __post_init__(self) -> None:
        check_fields(self)
        bad = _place_option_problem(self)
        if bad:
            raise InputError(f"PlaceOptions({bad}")


def _place_option_problem(o: PlaceOptions) -> str | None:
    """What of `o` is out of range (its field and value), or None."""
    finite = np.isfinite
    if o.zeta_min is not None and not 0 <= o.zeta_min < 1:
        return f"zeta_min): the least damping ratio must be in [0, 1), got {o.zeta_min:g}"
    if not (finite(o.amplitude_hz) and o.amplitude_hz > 0):
        return f"amplitude_hz): the amplitude must be > 0 Hz, got {o.amplitude_hz:g}"
    if o.max_sites is not None and o.max_sites < 1:
        return f"max_sites): must be >= 1, got {o.max_sites}"
    if o.safety_s is not None and not (finite(o.safety_s) and o.safety_s >= 0):
        return f"safety_s): the CCT margin must be >= 0 s, got {o.safety_s:g}"
    if o.max_iter < 1:
        return f"max_iter): must be >= 1, got {o.max_iter}"
    if not (finite(o.rtol) and 0 <= o.rtol < 1):
        return f"rtol): the relative saving must be in [0, 1), got {o.rtol:g}"
    return None


@dataclass(frozen=True)
class WarmStart:
    """Where `place` starts from.

    Attributes
    ----------
    base : dict or None
        Evaluations without storage if already done (`evaluations` at zero ratings).
    start : array_like or None, shape (n_sites,)
        First allocation (MW per site) instead of none, e.g. a uniform fleet that meets
        every target: the loop then starts feasible and every allocation it returns is
        at most as costly.
    evaluations : dict or None
        Evaluations of every contingency at `start` already simulated (e.g. a uniform
        fleet's first unstable clearing times, `evaluations` with scan="full"), used
        instead of simulating them again when `start` is on the 0.1 MW grid (unchanged
        by rounding); only the contingencies missing from it are simulated at `start`.
    """

    base: dict | None = None
    start: Any = None
    evaluations: dict | None = None


@dataclass
class _Setup:
    """What every iteration needs (see `place`): the evaluator (case, sites, pool,
    search), the contingencies, the damping model and the program's settings."""

    ev: Evaluator
    contingencies: tuple
    damping: Any
    zeta_min: float | None
    solve_kw: dict
    base: dict | None = None
    bound_ccts: dict = field(default_factory=dict)

    def verify(self, mw, which=None) -> dict:
        cons = self.contingencies if which is None else which
        return verify(self.ev, cons, mw, VerifyOptions(base=self.base))

    @property
    def sites(self) -> tuple:
        return self.ev.sites

    @property
    def tol(self) -> float:
        return self.ev.search.tol

    @property
    def upper(self) -> np.ndarray:
        return np.array([s.max_mw for s in self.sites])

    @property
    def cost(self) -> np.ndarray:
        return np.array([s.cost for s in self.sites])

    def sites_cost(self, mw) -> float:
        """Cost of the sites used by ratings mw (per-site costs)."""
        return float(
            np.broadcast_to(self.solve_kw["site_cost"], (len(self.sites),)) @ (np.asarray(mw) > 0)
        )


@dataclass
class _Point:
    """A simulated allocation: ratings (MW), evaluations, EM damping (or None), merit."""

    mw: np.ndarray
    ev: dict
    zeta: tuple | None
    merit: float
    feasible: bool


def place(
    case: str,
    contingencies,
    study: Study = Study(),
    options: PlaceOptions = PlaceOptions(),
    warm: WarmStart = WarmStart(),
    progress=None,
) -> PlacementResult:
    """Least-cost ESD allocation meeting every contingency's target CCT (and damping),
    verified by simulation (module docstring).

    Parameters
    ----------
    case : str
        Built-in case name or case file (workers load it by name).
    contingencies : sequence of Contingency
        Distinct names.
    study : Study, optional
        Sites, controller, CCT search, model settings and where the evaluations run.
    options : PlaceOptions, optional
        Damping requirement, sparsity, site costs, safety margin, iterations.
    warm : WarmStart, optional
        Evaluations without storage and a first allocation already known.
    progress : callable(str) or None, optional
        One line per step; None: this module's logger (INFO).

    Returns
    -------
    PlacementResult

    Raises
    ------
    InfeasibleError
        A contingency misses its target even with every site at its bound (simulated),
        or the damping rows cannot be met.
    InputError
        Bad settings (`check_damping_model`) or contingencies.
    SimulationError
        As the CCT search.
    """
    wall = time.perf_counter()
    contingencies = tuple(contingencies)
    o, tol = options, study.search.tol
    _check_settings(contingencies)
    check_damping_model(o.zeta_min, study.esd_model)
    sim = cached_simulator(case, study.model)
    _check_faults(sim.case, contingencies)
    sites = tuple(study.sites or candidate_sites(sim.case))
    with _LINEARISE:
        beta, damping = _linear_models(sim, sites, study.law, o.zeta_min, o.amplitude_hz)
    say = progress or logger.info
    with _pool(study) as rm:
        setup = _Setup(
            study.evaluator(rm, case, sites, beta),
            contingencies,
            damping,
            o.zeta_min,
            {
                "safety_s": 2 * tol if o.safety_s is None else o.safety_s,
                "max_sites": o.max_sites,
                "site_cost": o.site_cost,
            },
        )
        base = setup.base = warm.base or setup.verify(np.zeros(len(sites)))
        say("no storage: " + _cct_line(contingencies, base))
        result = _iterate(
            setup,
            base,
            _start(setup, warm.start, base, say, warm.evaluations),
            o.max_iter,
            o.rtol,
            say,
        )
    result.wall_time_s = time.perf_counter() - wall
    return result


def evaluations(
    case: str, contingencies, mw=None, study: Study = Study(), opts: VerifyOptions = VerifyOptions()
) -> dict:
    """Simulated CCT (and its gradient) of every contingency at ratings mw.

    Parameters
    ----------
    case : str
    contingencies : sequence of Contingency
    mw : array_like or None, optional
        MW per site of ``study.sites`` (default `candidate_sites`); None: no storage.
    study : Study, optional
        Sites, controller, search, model and where the runs go (as `place`).
    opts : VerifyOptions, optional
        base and scan (scan="full" with base: the first unstable clearing time, e.g. of
        a uniform fleet), brackets (where each bisection starts), gradient (False: CCTs
        only, no gradient runs).

    Returns
    -------
    dict
        Name -> `stabctl.placement.evaluation.evaluate` dict.

    Raises
    ------
    InputError, SimulationError
        As `place`.
    """
    contingencies = tuple(contingencies)
    sim = cached_simulator(case, study.model)
    _check_faults(sim.case, contingencies)
    sites = tuple(study.sites or candidate_sites(sim.case))
    with _LINEARISE:
        beta, _ = _linear_models(sim, sites, study.law, None, 0.0)
    mw = np.zeros(len(sites)) if mw is None else np.asarray(mw, float)
    with _pool(study) as rm:
        return verify(study.evaluator(rm, case, sites, beta), contingencies, mw, opts)


def baseline(
    case: str, faults, study: Study = Study(), opts: VerifyOptions = VerifyOptions()
) -> dict:
    """`evaluations` of every fault (`LineFault`) without storage: CCT by bisection and
    its gradient, by contingency name (study, opts as `evaluations`)."""
    return evaluations(
        case, [Contingency(f, study.search.t_max) for f in faults], None, study, opts
    )


def with_gain(faults, base: dict, gain_pct: float, tol: float = 1e-3) -> tuple:
    """Contingencies whose target is the CCT without storage (`base`, by name) raised by
    gain_pct %, rounded up to the tolerance lattice (s).  Raises InputError for
    gain_pct <= 0."""
    if not gain_pct > 0:
        raise InputError(f"target CCT gain must be > 0 %, got {gain_pct:g}")
    out = []
    for f in faults:
        name = Contingency(f, 1.0).name
        t = base[name]["cct_s"] * (1 + gain_pct / 100)
        out.append(Contingency(f, round(np.ceil(t / tol - 1e-9) * tol, 12)))
    return tuple(out)


def _pool(study: Study):
    """The study's run_map as is, or a `worker_pool` for one call."""
    if study.run_map is not None:
        return nullcontext(study.run_map)
    return worker_pool(study.runner.workers or 1, study.runner.scheduler)


def _check_faults(case, contingencies) -> None:
    """Every fault's buses and lines exist (before any simulation)."""
    from stabctl.dynamics.events import validate

    for c in contingencies:
        validate(case, c.fault.events(0.0), 0.0)


def _linear_models(sim, sites, controller, zeta_min, amplitude_hz):
    """Distribution factors (`sime.distribution_factors`) and, with zeta_min, the
    `damping.DampingModel`, both from one linearisation with an ESD input at every site;
    without zeta_min from the ESD columns of B alone (`linearise.esd_columns`: no A)."""
    from stabctl.dynamics.coi import machine_inertia
    from stabctl.smallsignal.damping import DampingModel, relay_df
    from stabctl.smallsignal.linearise import esd_columns, linearise
    from stabctl.stability.sime import distribution_factors

    case = sim.case
    buses = list(dict.fromkeys(s.bus for s in sites))
    sys = esd_columns(sim, buses) if zeta_min is None else linearise(sim, esd_buses=buses)
    beta = distribution_factors(
        sys, [s.bus for s in sites], case.machines.number, machine_inertia(case), case.base_mva
    )
    if zeta_min is None:
        return beta, None
    gain = relay_df(
        controller.deadband_hz, amplitude_hz, case.freq_hz, controller.hysteresis_hz
    ).real
    if not gain > 0:
        raise InputError(
            f"oscillation amplitude {amplitude_hz:g} Hz is inside the ESD "
            f"deadband ({controller.deadband_hz:g} Hz): the devices are idle "
            "there and add no damping"
        )
    return beta, DampingModel(sys, sites, gain, case.base_mva)


def check_damping_model(zeta_min: float | None, esd_model: str) -> None:
    """Refuse a damping requirement for devices other than ideal: the damping rows and
    the eigenvalues that confirm them (`stabctl.smallsignal.damping.DampingModel`) take
    each device as an ideal power input at its bus, without a WECC battery's converter
    lags and current limit, so they would not be the batteries' damping.

    Parameters
    ----------
    zeta_min : float or None
        The damping requirement (`PlaceOptions.zeta_min`; None: none).
    esd_model : {"ideal", "wecc"}
        The devices' model (`Study.esd_model`).

    Raises
    ------
    InputError
        zeta_min given with esd_model other than "ideal".
    """
    if zeta_min is not None and esd_model != "ideal":
        raise InputError(
            f"--zeta-min with --esd-model {esd_model}: the damping rows and their "
            "eigenvalue check take every device as an ideal power input (no converter "
            "lags or current limit), not a WECC battery; drop --zeta-min or use ideal devices"
        )


def _check_settings(contingencies) -> None:
    """The contingencies' own checks (PlaceOptions, SearchOptions and RunnerOptions check
    theirs when made)."""
    if not contingencies:
        raise InputError("no contingency given")
    names = [c.name for c in contingencies]
    if len(set(names)) != len(names):
        raise InputError(f"contingencies must differ, got {names}")
    bad = [c.name for c in contingencies if not c.target_cct_s > 0]
    if bad:
        raise InputError(f"contingency {', '.join(bad)}: the target CCT must be > 0 s")


# -- the trust-region loop ---------------------------------------------------------------


def _start(
    setup: _Setup, start, base: dict, say, known: dict | None = None
) -> tuple[np.ndarray, dict]:
    """The first allocation and its evaluations (no storage unless `start` is given;
    `known`: its evaluations already simulated, by contingency name)."""
    n = len(setup.sites)
    if start is None:
        return np.zeros(n), base
    start = np.asarray(start, float)
    if start.shape != (n,) or np.any(start < 0) or np.any(start > setup.upper + 1e-9):
        raise InputError(f"start: need {n} ratings within the site bounds (MW)")
    mw = _rounded(start, setup.sites)
    known = known if known is not None and np.array_equal(mw, start) else {}
    missing = [c for c in setup.contingencies if c.name not in known]
    ev = {
        **{c.name: known[c.name] for c in setup.contingencies if c.name in known},
        **(setup.verify(mw, missing) if missing else {}),
    }
    say(f"start {mw.sum():.1f} MW: " + _cct_line(setup.contingencies, ev))
    return mw, ev


def _iterate(setup: _Setup, base: dict, start, max_iter: int, rtol: float, say) -> PlacementResult:
    mw0, ev0 = start
    cuts = cuts_from(setup.contingencies, ev0, mw0)
    prices = _prices(setup, cuts_from(setup.contingencies, base, np.zeros_like(mw0)))
    cur = first = _point(setup, mw0, ev0, prices)
    best = cur if cur.feasible else None
    radius, iterations = float(setup.upper.max()), []
    checked: set[str] = set()
    solve_times: list[float] = []
    seen, tried = [], []
    message = f"stopped after {max_iter} simulated allocation(s) (cap)"
    for it in range(1, max_iter + 1):
        _prove_infeasible(setup, cuts, checked)
        alloc, rows = _trial(setup, cuts, cur.mw, radius, prices, solve_times)
        trial = _rounded(alloc.mw, setup.sites)
        predicted = cur.merit - _model_merit(setup, cuts, rows, trial, prices)
        if predicted <= rtol * max(setup.cost @ cur.mw, 1e-9) or np.array_equal(trial, cur.mw):
            message = (
                f"converged: the program predicts < {rtol:.0%} further saving"
                if cur.feasible
                else "stuck: the linearised program predicts no "
                "progress from the current allocation"
            )
            break
        new = _point(setup, trial, setup.verify(trial), prices)
        rho = (cur.merit - new.merit) / predicted
        iterations.append(_record(it, setup, new, alloc, rho, radius))
        say(
            f"iteration {it}: {trial.sum():.1f} MW at {np.count_nonzero(trial)} site(s), "
            f"{'meets every target' if new.feasible else 'misses'}, "
            f"gain {rho:.2f} x the program's prediction"
            + (" (worse than the last iterate)" if rho < 0 else "")
            + "; "
            + _cct_line(setup.contingencies, new.ev)
        )
        if new.feasible and (best is None or setup.cost @ new.mw < setup.cost @ best.mw):
            best = new
        tried.append(new)
        step = float(np.max(np.abs(trial - cur.mw)))
        if rho >= ACCEPT:
            cur, seen = new, [cur]
            radius = (
                min(2 * radius, setup.upper.max())
                if rho >= GOOD and step >= 0.9 * radius
                else radius
            )
        else:
            seen.append(new)
            radius = step / 2
        cuts = _secant_cuts(setup, cur, seen)
    restored = _restore(setup, tried, best, prices, iterations, say)
    if restored is not None:
        best, message = restored, message + "; then restored by scaling a near miss"
    if best is None:
        _prove_never_met(setup, cuts, [first, *tried], checked)
        message = f"no allocation met every target in {len(iterations)} simulated allocation(s)"
    end = best or cur
    return PlacementResult(
        allocation=_as_allocation(setup.sites, end.mw, solve_times),
        verified=best is not None,
        evaluations=end.ev,
        base=base,
        iterations=iterations,
        contingencies=setup.contingencies,
        damping=end.zeta,
        message=message,
        solve_times_s=solve_times,
    )


def _restore(setup: _Setup, tried, best, prices, iterations, say):
    """Feasibility restoration along a ray: the cheapest simulated allocation that missed
    only by a little (CCT shortfall summed <= RESTORE_MISS tolerances, no damping
    shortfall) is scaled up by each RESTORE_SCALE factor (within the site bounds) while
    still cheaper than the best verified allocation; the first scaled allocation that
    meets every target in simulation is returned (None if none does).  Each scaled
    allocation simulates first the contingencies the near miss missed, and the others
    only when those meet their targets (a miss there settles it).  Each one simulated is
    recorded in `iterations`."""

    def cost(p):
        return float(setup.cost @ p)

    near = [
        p
        for p in tried
        if not p.feasible
        and _misses_by(setup, p) <= RESTORE_MISS * setup.tol
        and (best is None or cost(p.mw) < cost(best.mw))
    ]
    if not near:
        return None
    p0 = min(near, key=lambda p: cost(p.mw))
    missed = [c for c in setup.contingencies if not c.met_by(p0.ev[c.name]["cct_s"])]
    for k in RESTORE_SCALE:
        mw = _rounded(np.minimum(k * p0.mw, setup.upper), setup.sites)
        if best is not None and cost(mw) >= cost(best.mw):
            return None
        ev = setup.verify(mw, missed) if missed else {}
        short = [c for c in missed if not c.met_by(ev[c.name]["cct_s"])]
        if short:
            iterations.append(
                _record(
                    len(iterations) + 1,
                    setup,
                    _Point(mw, ev, None, float("nan"), False),
                    _as_allocation(setup.sites, mw, []),
                    float("nan"),
                    0.0,
                    which=missed,
                )
            )
            say(f"near miss scaled x{k:g}: {mw.sum():.1f} MW, misses; " + _cct_line(missed, ev))
            continue
        rest = [c for c in setup.contingencies if c.name not in ev]
        new = _point(setup, mw, {**ev, **(setup.verify(mw, rest) if rest else {})}, prices)
        iterations.append(
            _record(
                len(iterations) + 1,
                setup,
                new,
                _as_allocation(setup.sites, mw, []),
                float("nan"),
                0.0,
            )
        )
        say(
            f"near miss scaled x{k:g}: {mw.sum():.1f} MW, "
            f"{'meets every target' if new.feasible else 'misses'}; "
            + _cct_line(setup.contingencies, new.ev)
        )
        if new.feasible:
            return new
    return None


def _misses_by(setup: _Setup, p: _Point) -> float:
    """CCT shortfall summed over the contingencies (s); inf with a damping shortfall."""
    if p.zeta is not None and damping_shortfall(p.zeta[1], setup.zeta_min) > 1e-4:
        return float("inf")
    return sum(max(0.0, c.target_cct_s - p.ev[c.name]["cct_s"]) for c in setup.contingencies)


def _secant_cuts(setup: _Setup, cur: _Point, seen) -> list:
    """Cuts at the current allocation, corrected through the allocations simulated since
    it was accepted and the one it was accepted from (`CCTCut.through`)."""
    return [
        c.through([(p.mw, p.ev[c.contingency]["cct_s"]) for p in seen])
        for c in cuts_from(setup.contingencies, cur.ev, cur.mw)
    ]


def _prices(setup: _Setup, cuts) -> tuple[float, float]:
    """Exact-penalty prices: mu_t (cost per s of CCT shortfall) ten times the dearest
    contingency's cheapest marginal cost of CCT at P = 0; mu_d (cost per unit damping
    shortfall) ten times the cost of every site at its bound."""
    cost = setup.cost
    rates = [
        np.min(cost[c.gradient > 0] / c.gradient[c.gradient > 0])
        for c in cuts
        if np.any(c.gradient > 0)
    ]
    full = float(cost @ setup.upper)
    mu_t = 10 * max(rates) if rates else full / setup.tol
    return mu_t, 10 * full


def _point(setup: _Setup, mw, ev: dict, prices) -> _Point:
    """Merit and feasibility of a simulated allocation."""
    zeta = None if setup.damping is None else setup.damping.em_damping(mw)
    short_t = sum(max(0.0, c.target_cct_s - ev[c.name]["cct_s"]) for c in setup.contingencies)
    short_d = 0.0 if zeta is None else damping_shortfall(zeta[1], setup.zeta_min)
    merit = float(
        setup.cost @ mw + setup.sites_cost(mw) + prices[0] * short_t + prices[1] * short_d
    )
    return _Point(
        mw=np.asarray(mw, float),
        ev=ev,
        zeta=zeta,
        merit=merit,
        feasible=short_t <= 1e-9 and short_d <= 1e-4,
    )


def damping_shortfall(zeta, zeta_min: float | None) -> float:
    """max over modes of kappa sqrt(1 - zeta^2) - zeta (>= 0), kappa = zeta_min /
    sqrt(1 - zeta_min^2): the normalised distance of the worst eigenvalue beyond the
    zeta_min line (the measure of `damping.DampingModel.rows`; ~ zeta_min - zeta); 0
    without a damping requirement (zeta_min None)."""
    z = np.asarray(zeta, float)
    if not z.size or zeta_min is None:
        return 0.0
    kappa = zeta_min / np.sqrt(1 - zeta_min**2)
    return float(max(0.0, np.max(kappa * np.sqrt(1 - z**2) - z)))


def _model_merit(setup: _Setup, cuts, rows, mw, prices) -> float:
    """The merit as the program sees it at ratings mw (linearised CCTs and damping)."""
    short_t = sum(max(0.0, c.target_s - c.predicted(mw)) for c in cuts)
    short_d = (
        0.0 if rows is None or not len(rows.b) else float(max(0.0, np.max(rows.A @ mw - rows.b)))
    )
    return float(setup.cost @ mw + setup.sites_cost(mw) + prices[0] * short_t + prices[1] * short_d)


def _trial(setup: _Setup, cuts, centre, radius, prices, solve_times, max_steps: int = 8):
    """The program's step from `centre` within `radius`; with damping rows, re-linearised
    at the step and solved again (same centre and radius) while the recomputed damping
    shortfall decreases: (allocation, damping rows used or None)."""
    kw = dict(setup.solve_kw, cct_penalty=prices[0], penalty=prices[1], trust=(centre, radius))
    dm = setup.damping
    rows = None if dm is None else dm.rows(centre, setup.zeta_min)
    alloc = sparse_allocation(setup.sites, cuts, damping=rows, **kw)
    solve_times.append(alloc.solve_time_s)
    if dm is None:
        return alloc, None
    short = damping_shortfall(dm.em_damping(alloc.mw)[1], setup.zeta_min)
    for _ in range(max_steps):
        if short <= 1e-4:
            break
        new_rows = dm.rows(alloc.mw, setup.zeta_min)
        new = sparse_allocation(setup.sites, cuts, damping=new_rows, **kw)
        solve_times.append(new.solve_time_s)
        new_short = damping_shortfall(dm.em_damping(new.mw)[1], setup.zeta_min)
        if new_short >= short:
            break
        alloc, rows, short = new, new_rows, new_short
    return alloc, rows


def _prove_infeasible(setup: _Setup, cuts, checked: set) -> None:
    """If the hard program over the whole box is infeasible, simulate the contingencies it
    names (not simulated so before) at their bound allocations (`_raise_if_infeasible`);
    InfeasibleError when one still misses its target at every one."""
    try:
        solve_allocation(setup.sites, cuts)
        return
    except InfeasibleError as exc:
        names = [n for n in exc.contingencies if n not in checked]
    if not names:
        return
    checked.update(names)
    _raise_if_infeasible(setup, [c for c in cuts if c.contingency in names])


def _prove_never_met(setup: _Setup, cuts, points, checked: set) -> None:
    """The loop ends without a verified allocation: the contingencies that missed their
    target at every allocation simulated (`points`) are simulated at their bound
    allocations from the latest cuts (`_raise_if_infeasible`), so that the plan gets a
    verdict on each (InfeasibleError) instead of a stop; those already simulated there by
    `_prove_infeasible` are not run again."""
    never = {
        c.name
        for c in setup.contingencies
        if all(not c.met_by(p.ev[c.name]["cct_s"]) for p in points)
    }
    if never:
        checked.update(never)
        best = {
            c.name: max(((p.ev[c.name]["cct_s"], p.mw) for p in points), key=lambda x: x[0])
            for c in setup.contingencies
            if c.name in never
        }
        _raise_if_infeasible(
            setup,
            [c for c in cuts if c.contingency in never],
            {
                n: f"; its best over the {len(points)} allocation(s) the loop simulated "
                f"{cct:.3f} s at {mw.sum():.1f} MW"
                for n, (cct, mw) in best.items()
            },
        )


def bound_allocations(cut, upper) -> list:
    """The allocations at which a contingency's infeasibility is simulated (MW per site,
    each (n_sites,)): every site at its bound, then, when it differs, only the sites whose
    rating raises the contingency's linearised CCT (gradient > 0) at their bound, the
    others empty (the box maximum of its cut, `program.diagnose`).  The second keeps out a
    device that lowers the CCT, which the paper's law can do (docs/placement.md section 8:
    on IEEE 39 every site at its bound lowers fault 21-22's CCT where 3 of them raise it).

    Parameters
    ----------
    cut : CCTCut
        The contingency's linearised CCT (its gradient in s/MW, shape (n_sites,)).
    upper : array_like, shape (n_sites,)
        Every site's largest rating (MW).

    Returns
    -------
    list of numpy.ndarray
        One or two allocations, shape (n_sites,) each (MW).
    """
    ub = np.asarray(upper, float)
    helpful = np.where(cut.gradient > 0, ub, 0.0)
    if helpful.any() and not np.array_equal(helpful, ub):
        return [ub, helpful]
    return [ub]


def _raise_if_infeasible(setup: _Setup, cuts, also: dict | None = None) -> None:
    """Simulate the contingency of every cut at its bound allocations (`bound_allocations`:
    every site at its bound, then only the sites that raise its linearised CCT), the
    latter only when the former misses; InfeasibleError naming the contingencies that miss
    their target at every one (each CCT simulated once per allocation, `_Setup.bound_ccts`;
    also: name -> text added to its verdict)."""
    by_name = {c.name: c for c in setup.contingencies}
    tried: dict[str, list] = {}
    for cut in cuts:
        c = by_name[cut.contingency]
        tried[c.name] = []
        for mw in bound_allocations(cut, setup.upper):
            key = (c.name, mw.tobytes())
            if key not in setup.bound_ccts:
                setup.bound_ccts[key] = setup.verify(mw, [c])[c.name]["cct_s"]
            tried[c.name].append((mw, setup.bound_ccts[key]))
            if c.met_by(tried[c.name][-1][1]):
                break
    failing = [
        by_name[n] for n, t in tried.items() if all(not by_name[n].met_by(cct) for _, cct in t)
    ]
    if failing:
        raise InfeasibleError(
            "infeasible: "
            + "; ".join(
                _infeasible_text(c, tried[c.name], _no_storage_cct(setup, c))
                + (also or {}).get(c.name, "")
                for c in failing
            ),
            [c.name for c in failing],
        )


def _no_storage_cct(setup: _Setup, c: Contingency) -> float | None:
    """The contingency's CCT without storage (s), when the loop has it."""
    return (setup.base or {}).get(c.name, {}).get("cct_s")


def _infeasible_text(c: Contingency, tried, base_cct: float | None = None) -> str:
    """One proven-infeasible contingency: its CCT at each bound allocation simulated, and
    its CCT without storage (`base_cct`, s, when known), said when every allocation
    lowers it."""
    at = [
        f"{cct:.3f} s with every candidate site at its bound ({mw.sum():.0f} MW)"
        if k == 0
        else f"{cct:.3f} s with only the {np.count_nonzero(mw)} site(s) that raise its "
        f"linearised CCT at their bound ({mw.sum():.0f} MW)"
        for k, (mw, cct) in enumerate(tried)
    ]
    ccts = [cct for _, cct in tried if cct is not None]
    without = ""
    if base_cct is not None:
        lower = bool(ccts) and max(ccts) < base_cct
        without = f" ({base_cct:.3f} s without storage" + (
            ": the devices lower it, docs/placement.md section 8)" if lower else ")"
        )
    return (
        f"{c.describe()} reaches a CCT of only {' and '.join(at)} against its target "
        f"{c.target_cct_s:.3f} s, simulated{without}"
    )


def _rounded(mw, sites) -> np.ndarray:
    """Ratings rounded up to 0.1 MW (within the bounds); below MIN_MW not installed."""
    mw = np.asarray(mw, float)
    ub = np.array([s.max_mw for s in sites])
    up = np.minimum(np.ceil(mw * 10 - 1e-6) / 10, ub)
    return np.where(mw >= MIN_MW, up, 0.0)


def _record(it, setup: _Setup, p: _Point, alloc: Allocation, rho, radius, which=None) -> dict:
    """One simulated allocation for `PlacementResult.iterations`; which: the contingencies
    simulated there (default all)."""
    which = setup.contingencies if which is None else which
    return {
        "iteration": it,
        "total_mw": total_mw(p.mw),
        "n_sites": int(np.count_nonzero(p.mw)),
        "mw_by_site": [float(x) for x in p.mw],
        "meets_targets": p.feasible,
        "rho": float(rho),
        "radius_mw": float(radius),
        "cct_s": {c.name: p.ev[c.name]["cct_s"] for c in which},
        "n_simulations": sum(p.ev[c.name]["n_simulations"] or 0 for c in which),
        "predicted_cct_s": alloc.predicted_cct_s,
        "min_damping": None if p.zeta is None else float(np.min(p.zeta[1])),
        "solve_time_s": alloc.solve_time_s,
        "solve_wall_s": alloc.wall_time_s,
    }


def _as_allocation(sites, mw, solve_times) -> Allocation:
    cost = np.array([s.cost for s in sites])
    return Allocation(
        sites=tuple(sites),
        mw=np.asarray(mw, float),
        objective=float(cost @ mw),
        solve_time_s=float(solve_times[-1]) if solve_times else 0.0,
        wall_time_s=0.0,
    )


def _cct_line(contingencies, ev) -> str:
    return ", ".join(
        f"{c.name} {ev[c.name]['cct_s']:.3f}/{c.target_cct_s:.3f} s" for c in contingencies
    )
