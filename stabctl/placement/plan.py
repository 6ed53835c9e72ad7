"""A planner's placement: least-cost ESD sites, MW and MWh such that every screened fault
is stable when cleared at its required clearing time, at every load level planned for
(docs/placement.md, section 7).

Verification (`stabctl.placement.evaluation.check`): a contingency is met at an allocation
when the run cleared at its required clearing time (`stabctl.placement.requirements`) is
stable; the contingencies the program is solved for (the active set) are moreover met by
their first unstable clearing time (`stabctl.placement.loop`).

Constraint generation (`plan`): every contingency is first simulated once without storage,
cleared at its required time; those that fail are the candidates, the most binding of
them (smallest CCT without storage relative to the requirement, up to `n_active`) the
first active set.  Each round solves the verified trust-region loop
(`stabctl.placement.loop.place`) for the active set, warm-started from the last
allocation with the evaluations already simulated, then checks every contingency at the
allocation (one run each) and adds those that fail; it ends when none fails.  A round
whose loop verifies no allocation restarts, once per plan, from the least uniform fleet
meeting the active set (`_uniform_start`).  When the last round ends with an allocation
not yet checked on every contingency (it set some aside, or found the uniform fleet), the
allocation is checked then (`_check_last_allocation`).  The energies are then sized
(`stabctl.placement.energy`) and, when asked, the references computed
(`stabctl.placement.references`).

The run's end: every check is judged in the CCT search's window (the fault start +
T_AFTER_FAULT).  A contingency whose CCT search (without storage, or with the
allocation) found its unstable end separating late in that window
(`stabctl.stability.cct.CCTResult.run_end_check`) has its check run again T_AFTER_FAULT s
longer at the end (`_run_end`, one run each); one that loses synchronism there is named
NOT CONVERGED IN THE RUN'S END (`PlanResult.run_end`): the plan is verified in the
window only.  A contingency N-1 insecure (unstable even when cleared at once, by its CCT
search) is set aside as such with `PlanOptions.drop_infeasible`, else raised.
"""

from __future__ import annotations

import logging
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np

from stabctl.dynamics.options import ModelOptions
from stabctl.errors import (
    InputError,
    NumericalInstabilityError,
    SimulationError,
    advice,
    check_fields,
    counted,
    require_instance,
    require_items,
    require_number,
)
from stabctl.placement.context import PlanContext
from stabctl.placement.energy import mwh_per_mw, size_energy
from stabctl.placement.evaluation import TARGET_SLACK_S, VerifyOptions
from stabctl.placement.loop import (
    PlaceOptions,
    Study,
    WarmStart,
    _as_allocation,
    _pool,
    check_damping_model,
    evaluations,
    place,
)
from stabctl.placement.memo import Memo
from stabctl.placement.program import InfeasibleError, candidate_sites, total_mw
from stabctl.placement.references import (
    faults_alone,
    half_step,
    least_pct,
    least_uniform,
    margins,
    uniform_fleet,
)
from stabctl.placement.requirements import CostModel, Requirement, contingencies_of, describe
from stabctl.progress import Heartbeat
from stabctl.stability.cct import RUN_END_KEYS, T_AFTER_FAULT, run_end_lost

logger = logging.getLogger(__name__)


@dataclass
class PlanResult:
    """Outcome of `plan`.

    sites: candidate sites; mw, mwh: rating (MW) and usable energy (MWh) per site
    (n_sites,); cost: `CostModel.split`; verified: every contingency checked stable at its
    required clearing time (and the active ones by their CCT, and the sized energies);
    contingencies: one row per contingency (`rows`); rounds: one dict per round of
    constraint generation; active: names of the contingencies the program was solved
    for; message: why it stopped; n_simulations: runs simulated in all; wall_time_s.
    uniform, alone: the references when asked (`least_uniform`, `faults_alone`); half_step: the
    tightest contingencies again at half the step (`half_step`) when asked; out_of_scope:
    contingencies unstable when cleared at once; infeasible, set_aside: the proofs and
    names of those set aside as infeasible; not_simulable: name -> why of those set aside
    as not simulable without storage (their fault fails while on: `PlanOptions.
    drop_infeasible`); n1_insecure: name -> the verdict of those set aside as N-1
    insecure (unstable even when cleared at once, by their CCT search without storage);
    run_end: {"window_s" (the checks' window after the fault start, s), "checked" (the
    contingencies whose check was run T_AFTER_FAULT s longer, `_run_end`),
    "not_converged" (those of them that lose synchronism there: verified in the window
    only), "cct_no_storage_not_converged" (those whose CCT without storage is NOT
    CONVERGED IN THE RUN'S END, as `stabctl cct` says)}.
    """

    case: str
    requirement: str
    load_levels: tuple
    sites: tuple
    mw: np.ndarray
    mwh: np.ndarray
    cost: dict
    verified: bool
    contingencies: list
    rounds: list
    active: list
    message: str
    energy: list = field(default_factory=list)
    out_of_scope: list = field(default_factory=list)
    infeasible: list = field(default_factory=list)
    set_aside: list = field(default_factory=list)
    not_simulable: dict = field(default_factory=dict)
    n1_insecure: dict = field(default_factory=dict)
    run_end: dict = field(default_factory=dict)
    uniform: dict | None = None
    alone: list = field(default_factory=list)
    half_step: dict | None = None
    n_simulations: int = 0
    wall_time_s: float = 0.0

    @property
    def total_mw(self) -> float:
        """Rating of every device, MW."""
        return _as_allocation(self.sites, self.mw, []).total_mw

    def allocation(self) -> list[dict]:
        """Installed sites: bus, machine, MW, MWh, energy absorbed and delivered (MJ, the
        largest over the verifying runs)."""
        rows = _as_allocation(self.sites, self.mw, []).rows()
        for r, j in zip(rows, np.nonzero(self.mw > 0)[0]):
            r.update(mwh=float(self.mwh[j]), **(self.energy[j] if self.energy else {}))
        return rows

    def to_dict(self) -> dict:
        """JSON-ready summary (MW, MWh, s, cost units)."""
        met = [c for c in self.contingencies if c["met"]]
        return {
            "verified": self.verified,
            "message": self.message,
            "requirement": self.requirement,
            "load_levels": list(self.load_levels),
            "allocation": self.allocation(),
            "total_mw": self.total_mw,
            "total_mwh": float(self.mwh.sum()),
            "n_sites": int(np.count_nonzero(self.mw)),
            "n_buses": len({r["bus"] for r in self.allocation()}),
            "cost": self.cost,
            "n_contingencies": len(self.contingencies),
            "n_met": len(met),
            "active": self.active,
            "out_of_scope": self.out_of_scope,
            "infeasible": self.infeasible,
            "set_aside": self.set_aside,
            "not_simulable": self.not_simulable,
            "n1_insecure": self.n1_insecure,
            "run_end": self.run_end,
            "contingencies": self.contingencies,
            "rounds": self.rounds,
            "n_simulations": self.n_simulations,
            "wall_time_s": self.wall_time_s,
            "uniform": self.uniform,
            "alone": self.alone,
            "half_step": self.half_step,
        }


#: the load levels a plan takes: each multiplies every contingency's searches (a plan
#: of 5 000 levels solved their power flows for minutes before saying a word)
MAX_LOAD_LEVELS = 20


def _load_levels(load_levels) -> tuple:
    """The load levels (fractions of the base load), each once, in the order given.
    Raises InputError for none, one that is not a number > 0, or more than
    MAX_LOAD_LEVELS; WrongTypeError for a text or an item not a number."""
    name = advice("load_levels", "--load-levels")
    items = require_items(load_levels, name, "a list of load levels (fractions of the base load)")
    levels = tuple(dict.fromkeys(require_number(x, f"{name}: a load level") for x in items))
    if not levels or any(not (np.isfinite(x) and x > 0) for x in levels):
        raise InputError(f"{name}: load levels must be numbers > 0, got {list(items)}")
    if len(levels) > MAX_LOAD_LEVELS:
        raise InputError(
            f"{name}: {len(levels)} load levels, more than "
            f"the {MAX_LOAD_LEVELS} a plan takes (each multiplies every contingency's CCT "
            "searches; a plan's levels are a handful, e.g. 0.9,1.0,1.1)"
        )
    return levels


@dataclass(frozen=True)
class PlanOptions:
    """Settings of a plan (`plan`).

    Attributes
    ----------
    load_levels : tuple of float
        Load levels (fractions of the base load) every fault is verified at; default (1,).
    overrides : dict or None
        Fault name -> Requirement (`read_requirements`) instead of the global one.
    cost : CostModel or None
        Costs (default 1 per MW: least MW).
    brackets : dict or None
        Fault name -> [stable, unstable] clearing times without storage at the base load
        (s), e.g. a screening's, where the CCT searches start; [t, None]: still stable
        when cleared at t (a screening's limit), known stable at any requirement up to t.
    n_active : int
        Contingencies in the first active set (the most binding of those unstable
        without storage); default 12.
    max_rounds : int
        Rounds of constraint generation at most.
    place : PlaceOptions
        Every round's verified loop (`stabctl.placement.loop.place`): allocations simulated
        per round at most (``max_iter``, default 6), damping (``zeta_min``,
        ``amplitude_hz``, verified by the loop for the allocation as a whole) and
        sparsity (``max_sites``).
    uniform, alone : bool
        Also the least uniform fleet and each fault's own least allocation meeting the
        same requirements (`stabctl.placement.references`).
    margins_tol : float or None
        Also the clearing margin with the allocation of every contingency the program
        was not solved for, to margins_tol (s), up to margins_cap_s (s; `margins`);
        None: those are only checked at their required time (margin >= 0 known).
    margins_cap_s : float
    scope_stable_at_once : bool
        Leave out (and list in `PlanResult.out_of_scope`) the contingencies unstable
        already when cleared at once (the line trip alone, at their load level), which no
        required clearing time can describe; default True.  False: they stay in, and
        are infeasible unless storage makes the trip alone stable.
    drop_infeasible : bool
        A contingency proven infeasible (named by `InfeasibleError`) is set aside, listed
        in `PlanResult.infeasible`, and the others are planned for; so is one whose fault
        cannot be simulated without storage while it is on, in a case with converters
        (one run each with the fault held on for the search limit first:
        `stabctl.stability.cct.fault_on_failure`), listed in `PlanResult.not_simulable`.
        Default False: the error is raised.
    half_step_n : int
        Also simulate the half_step_n contingencies of least clearing margin again at
        half the integration step (`half_step`); default 0: not done.
    half_step_verdicts : bool
        Also simulate every contingency of a verified plan again at half the step,
        cleared at its required time with the allocation (`half_step`: its verdict shown
        converged, as `stabctl place` does; a plan's margins are often 0 ms); default
        False.
    memo : Memo or None
        Keeps each simulation job's result as it finishes and hands back those it holds
        (`stabctl.placement.memo`): the same plan run again after an interrupt simulates
        only what had not finished, and gives the same plan; default None: not kept.

    Raises
    ------
    WrongTypeError
        A field of another type (`stabctl.errors.check_fields`; place not PlaceOptions).
    InputError
        No load level, or one not > 0, or more than MAX_LOAD_LEVELS (each held once);
        n_active or max_rounds < 1; half_step_n < 0; margins_tol or margins_cap_s not
        > 0.
    """

    load_levels: tuple = (1.0,)
    overrides: dict | None = None
    cost: CostModel | None = None
    brackets: dict | None = None
    n_active: int = 12
    max_rounds: int = 6
    place: PlaceOptions = PlaceOptions(max_iter=6)
    uniform: bool = False
    alone: bool = False
    margins_tol: float | None = None
    margins_cap_s: float = 0.1
    scope_stable_at_once: bool = True
    drop_infeasible: bool = False
    half_step_n: int = 0
    half_step_verdicts: bool = False
    memo: Memo | None = None

    def __post_init__(self) -> None:
        check_fields(self)
        object.__setattr__(self, "load_levels", _load_levels(self.load_levels))
        require_instance(self.place, PlaceOptions, "PlanOptions(place)")
        if self.memo is not None:
            require_instance(self.memo, Memo, "PlanOptions(memo)")
        for name in ("n_active", "max_rounds"):
            if getattr(self, name) < 1:
                raise InputError(f"PlanOptions({name}): must be >= 1, got {getattr(self, name)}")
        if self.half_step_n < 0:
            raise InputError(f"PlanOptions(half_step_n): must be >= 0, got {self.half_step_n}")
        for name in ("margins_tol", "margins_cap_s"):
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and value > 0):
                raise InputError(f"PlanOptions({name}): must be > 0 s, got {value:g}")


def plan(
    case: str,
    faults,
    requirement: Requirement,
    options: PlanOptions = PlanOptions(),
    study: Study = Study(),
    progress=None,
) -> PlanResult:
    """Least-cost ESD sites, MW and MWh meeting `requirement` on every fault at every load
    level, verified by simulation (module docstring).

    Parameters
    ----------
    case : str
        Built-in case name or case file (workers load it by name).
    faults : sequence of LineFault
        Every contingency to meet (e.g. a whole screening).
    requirement : Requirement
        Global requirement (``options.overrides`` per fault).
    options : PlanOptions, optional
        Load levels, costs, screening brackets, rounds, the loop's settings, references.
    study : Study, optional
        Candidate sites, controller, CCT tolerance and search limit, model settings,
        workers or Dask scheduler, or a run_map kept open by the caller
        (`stabctl.placement.loop.Study`).
    progress : callable(str) or None
        One line per step; None: to this module's logger (level INFO, `stabctl.progress`).

    Returns
    -------
    PlanResult

    Raises
    ------
    InfeasibleError
        A contingency misses its requirement even with every site at its bound (named
        with its load level).
    InsecureContingency
        A contingency N-1 insecure (its CCT search without storage: unstable even when
        cleared at once), unless ``options.drop_infeasible`` sets it aside.
    InputError
        No faults, bad settings (`check_damping_model`), a fault unstable already when
        cleared at once, a contingency's target at or above the search limit
        ``study.search.t_max`` (named with its target).
    PowerFlowError, CaseError
        A load level without a power flow or a valid initial state (named).
    """
    wall = time.perf_counter()
    o = options
    faults = list(faults)
    if not faults:
        raise InputError("no contingency given")
    check_damping_model(o.place.zeta_min, study.esd_model)
    levels = o.load_levels  # checked, each once (PlanOptions)
    freq_hz, sites = _case_at_levels(case, study.model, levels, study.sites)
    say = Heartbeat(progress or logger.info)
    try:
        result = _planned(case, faults, requirement, o, study, say, freq_hz, sites, levels)
    except SimulationError as exc:
        if (
            o.drop_infeasible
            or isinstance(exc, NumericalInstabilityError)
            or not _converters(case, study.model)
        ):
            raise
        raise type(exc)(
            f"{exc}; a plan with --set-aside-infeasible (PlanOptions.drop_infeasible) sets "
            "aside a contingency whose fault cannot be simulated without storage",
            result=exc.result,
        ) from exc
    result.wall_time_s = time.perf_counter() - wall
    return result


def _planned(case, faults, requirement, o: PlanOptions, study, say, freq_hz, sites, levels):
    """`plan`'s rounds, references and result (its wall time not yet set)."""
    with _pool(study) as pool_map, say:
        pl = PlanContext(
            case,
            sites,
            o.cost or CostModel(),
            study.law,
            study.model,
            None,
            study.search.tol,
            study.search.t_max,
            say,
            place=o.place,
            drop_infeasible=o.drop_infeasible,
            brackets=o.brackets,
            esd_model=study.esd_model,
            critical_reference=study.critical_reference,
        )
        pl.run_map = pl.counting(o.memo.wrap(pool_map) if o.memo else pool_map, say)
        kw = replace(
            study,
            sites=sites,
            run_map=pl.run_map,
            controller=pl.controller,
            case_digest=pl.case_digest,  # every round on the content the plan first read
        )
        cons = _contingencies(pl, faults, requirement, o.overrides, freq_hz, levels, kw)
        cons, failing, checks, out = _without_storage(
            pl, cons, len(faults), len(levels), o.scope_stable_at_once
        )
        cons = _not_monotone(pl, cons, failing, checks, kw)
        result = _generate(pl, cons, failing, checks, o.n_active, o.max_rounds, kw)
        result.out_of_scope, result.load_levels = sorted(out), levels
        result.requirement = describe(requirement, o.overrides)
        result.infeasible, result.set_aside = list(pl.infeasible), list(pl.set_aside)
        result.not_simulable = dict(pl.not_simulable)
        result.n1_insecure = dict(pl.n1_insecure)
        kept = {r["name"] for r in result.contingencies}
        _references(
            pl,
            tuple(c for c in cons if c.name in kept),
            [c for c in failing if c.name in kept],
            result,
            kw,
            o,
        )
    result.n_simulations = pl.n_runs
    return result


def _case_at_levels(case: str, model: ModelOptions, levels, sites) -> tuple:
    """The case's frequency (Hz) and the candidate sites (given, or `candidate_sites`),
    once its power flow at every load level is known to solve.  Raises PowerFlowError or
    CaseError naming the load level."""
    from stabctl.stability.cct import cached_simulator

    for x in levels:
        cached_simulator(case, model, load=x)
    sim = cached_simulator(case, model)
    return sim.case.freq_hz, tuple(sites or candidate_sites(sim.case))


def _contingencies(
    pl: PlanContext, faults, requirement: Requirement, overrides, freq_hz, levels, kw
) -> tuple:
    """Every fault at every load level with its required clearing time
    (`contingencies_of`); where a requirement is a CCT gain, the CCTs without storage of
    every contingency are simulated first (into pl.base)."""
    every = contingencies_of(faults, Requirement(cct_s=pl.t_max), freq_hz, pl.tol, levels)
    if pl.drop_infeasible:
        _set_aside_not_simulable(pl, every)
    every = tuple(c for c in every if c.name not in pl.not_simulable)
    if requirement.needs_base or any(r.needs_base for r in (overrides or {}).values()):
        pl.say(f"CCT without storage of {counted(len(every), 'contingency', 'contingencies')}")
        pl.add_base(every, pl.brackets, kw)
    aside = {**pl.not_simulable, **pl.n1_insecure}
    cons = contingencies_of(faults, requirement, freq_hz, pl.tol, levels, overrides, pl.base, aside)
    _check_search_limit(pl, cons, requirement, overrides)
    held = [c.name for c in cons if _held_at_limit(pl, c, overrides, requirement)]
    if held:
        pl.say(
            f"{counted(len(held), 'contingency', 'contingencies')} stable without storage "
            f"when cleared at the search limit t_max = {pl.t_max:g} s (a CCT above it: no "
            f"gain a search can show), held to stay stable cleared there: {', '.join(held)}"
        )
    return cons


def _converters(case: str, model: ModelOptions) -> bool:
    """Whether the case has converters (current sources: `_set_aside_not_simulable`)."""
    from stabctl.stability.cct import cached_simulator

    return bool(len(cached_simulator(case, model).case.converters))


def _set_aside_not_simulable(pl: PlanContext, every) -> None:
    """Set aside (into pl.not_simulable) the contingencies whose fault cannot be
    simulated without storage while it is on, up to the search limit (one short run
    each: `PlanContext.simulable`), in a case with converters: current sources, whose
    network equations can have no solution facing a fault of almost no impedance
    (`stabctl.network.solution.no_solution_hint`).  Without converters the faulted
    network of machines and loads is not run in advance."""
    if not _converters(pl.case, pl.model):
        return
    pl.say(
        f"{counted(len(every), 'contingency', 'contingencies')}: each fault held on for the "
        f"search limit t_max = {pl.t_max:g} s without storage (can it be simulated?)"
    )
    pl.simulable(every)
    for name, why in pl.not_simulable.items():
        pl.say(f"set aside, not simulable without storage: {name}: {why}")


def _held_at_limit(pl: PlanContext, c, overrides, requirement: Requirement) -> bool:
    """Whether contingency `c`'s gain requirement holds it at the search limit: stable
    without storage when cleared at t_max (`Requirement.target_s`)."""
    req = (overrides or {}).get(c.fault_name, requirement)
    robust = (pl.base.get(c.name) or {}).get("above_t_max", False)
    return bool(req.needs_base and robust and c.target_cct_s <= pl.t_max + TARGET_SLACK_S)


def _check_search_limit(pl: PlanContext, cons, requirement: Requirement, overrides) -> None:
    """InputError naming the first contingency whose target reaches the CCT search limit
    t_max: every CCT searched is at most t_max, so no allocation could be shown to meet
    it, and the loop would call it infeasible, its CCT "only" t_max with every site at
    its bound (the search limit, not the storage, bounding it).  A contingency a gain
    holds at t_max (stable there without storage: `_held_at_limit`) is no such target."""
    for c in cons:
        if c.target_cct_s < pl.t_max - TARGET_SLACK_S:
            continue
        if _held_at_limit(pl, c, overrides, requirement):  # robust: verified at t_max
            continue
        req = (overrides or {}).get(c.fault_name, requirement)
        cct = (pl.base.get(c.name) or {}).get("cct_s") if req.needs_base else None
        without = "" if cct is None else f", its CCT without storage {cct:.3f} s"
        raise InputError(
            f"{c.describe()}: its target CCT {c.target_cct_s:.3f} s ({req.describe()}"
            f"{without}) is at or above the CCT search limit t_max = {pl.t_max:g} s "
            "(--t-max), which bounds every CCT searched, with or without storage: raise "
            "--t-max above the target, or lower the requirement (--required-clearing-cycles, "
            "--target-cct-gain, --target-cct-s or the fault list's own columns)"
        )


def _without_storage(
    pl: PlanContext, cons, n_faults: int, n_levels: int, scope_stable_at_once: bool
) -> tuple:
    """Each contingency cleared at its required time without storage (one run each, but
    those the screening knows stable): (the contingencies in scope, those failing, name ->
    check, names out of scope: unstable even when cleared at once, when
    scope_stable_at_once)."""
    known = _stable_by_screening(cons, pl.brackets)
    pl.say(
        f"{counted(len(cons), 'contingency', 'contingencies')} ({counted(n_faults, 'fault')} "
        f"x {counted(n_levels, 'load level')}): each cleared at its required time without "
        f"storage ({len(known)} known stable there from the screening)"
    )
    checks = pl.check([c for c in cons if c.name not in known], np.zeros(len(pl.sites)))
    failing = [c for c in cons if c.name in checks and not checks[c.name]["stable_at_check"]]
    out = _out_of_scope(pl, failing) if scope_stable_at_once else set()
    if out:
        pl.say(
            "out of scope (unstable even when cleared at once, the line trip alone): "
            + ", ".join(sorted(out))
        )
    cons = tuple(c for c in cons if c.name not in out)
    failing = [c for c in failing if c.name not in out]
    pl.say(
        f"{len(failing)} of {len(cons)} unstable without storage"
        + (": " + ", ".join(c.name for c in failing[:12]) if failing else "")
        + (" ..." if len(failing) > 12 else "")
    )
    return cons, failing, {**{n: _STABLE for n in known}, **checks}, out


def _not_monotone(pl: PlanContext, cons, failing, checks, study: Study) -> tuple:
    """`cons` less the contingencies whose verdict without storage is not monotone in the
    clearing time: stable cleared at their required time T_c (one run), yet with a CCT
    without storage below it (a CCT search each, but those a gain requirement already
    made), so that no check at T_c can tell whether storage meets the requirement
    (Kundur's 13-101 at the default step, unstable cleared at 0.409-0.600 s and stable at
    0.601 s, was "VERIFIED, 0 MW" for a required CCT of 0.601 s).  They are set aside,
    named with the reason, when the plan sets infeasible ones aside; else an InputError
    names them.  Those the screening found stable at T_c are taken as it says."""
    unstable = {c.name for c in failing}
    stable = [
        c for c in cons if c.name in checks and c.name not in unstable and c.target_cct_s < pl.t_max
    ]
    if not stable:
        return cons
    pl.say(
        f"CCT without storage of the {counted(len(stable), 'contingency', 'contingencies')} "
        "stable at the required time (a stable clearing above a CCT meets no requirement)"
    )
    pl.add_base(stable, pl.brackets, study)
    cons, stable = pl.planned(cons), list(pl.planned(stable))
    why = {
        c.name: (
            f"not monotone: {c.name}: stable cleared at its required {c.target_cct_s:.3f} s "
            "without storage, "
            f"yet its CCT without storage is {pl.base[c.name]['cct_s']:.3f} s (unstable "
            "cleared between them): a verdict not monotone in the clearing time, which the "
            "placement's checks at the required time cannot size storage for"
        )
        for c in stable
        if not c.met_by(pl.base[c.name]["cct_s"])
    }
    if not why:
        return cons
    if not pl.drop_infeasible:
        raise InputError(
            "; ".join(why.values())
            + " (--set-aside-infeasible, PlanOptions.drop_infeasible, sets it aside, named; "
            "or require a clearing time at or below its CCT)"
        )
    pl.infeasible.extend(why.values())
    pl.set_aside.extend(sorted(why))
    pl.say("set aside, its verdict not monotone: " + ", ".join(sorted(why)))
    return tuple(c for c in cons if c.name not in why)


def _references(
    pl: PlanContext, cons, failing, result: PlanResult, kw: Study, o: PlanOptions
) -> None:
    """What `plan` adds to a result when asked: the clearing margins (then the half-step
    check, which ranks by them), the least uniform fleet and each binding fault alone.
    They are independent, so they run at the same time (one thread each, sharing the
    worker pool: fewer idle workers at the end of each one's batches)."""

    def margins_and_half_step():
        if o.margins_tol is not None:
            margins(pl, cons, result, o.margins_tol, o.margins_cap_s, kw)
        if (o.half_step_n > 0 or o.half_step_verdicts) and result.verified:
            result.half_step = half_step(
                pl, cons, result, o.half_step_n, kw, verdicts=o.half_step_verdicts
            )

    with ThreadPoolExecutor(max_workers=3) as threads:
        m = threads.submit(margins_and_half_step)
        u = threads.submit(least_uniform, pl, cons, failing, kw) if o.uniform else None
        a = (
            threads.submit(faults_alone, pl, cons, result, o.place.max_iter, kw)
            if o.alone
            else None
        )
        m.result()
        result.uniform = None if u is None else u.result()
        result.alone = [] if a is None else a.result()


#: A check known without a run (stable, no energy figures).
_STABLE = {"stable_at_check": True, "energy_mj": [], "site_excursion_s": [], "check_s": None}


def _stable_by_screening(cons, brackets) -> set:
    """Names of base-load contingencies the screening found stable when cleared at their
    required time or later without storage (its stable end is at least the requirement).
    """
    return {
        c.name
        for c in cons
        if brackets
        and c.load == 1.0
        and c.fault_name in brackets
        and c.met_by(brackets[c.fault_name][0])
    }


def _out_of_scope(pl: PlanContext, failing) -> set:
    """Names of the contingencies of `failing` unstable without storage even when cleared
    at once (one run each, the line trip alone)."""
    if not failing:
        return set()
    at_once = pl.check([replace(c, target_cct_s=0.0) for c in failing], np.zeros(len(pl.sites)))
    return {n for n, ck in at_once.items() if not ck["stable_at_check"]}


def _most_binding(failing, brackets, base: dict, n: int) -> list:
    """The n contingencies of `failing` with the least ratio of the CCT without storage to
    the requirement: simulated (base) or else the screening's (base load; none: last),
    the heavier load level first among equals.  With a screening no run is needed: the
    CCTs without storage of the rest are simulated only if they are added."""

    def severity(c):
        cct = (
            base[c.name]["cct_s"]
            if c.name in base
            else (brackets or {}).get(c.fault_name, (None,))[0]
        )
        return (np.inf if cct is None else cct / c.target_cct_s, -c.load, c.name)

    return sorted(failing, key=severity)[:n]


@dataclass
class _Rounds:
    """Constraint generation between rounds: the contingencies still planned for (cons),
    the allocation (mw, MW per site) and its checks (name -> check dict), the active set
    and its evaluations (evs), one dict per round, and the verdict so far."""

    cons: tuple
    checks: dict
    mw: np.ndarray
    active: list = field(default_factory=list)
    evs: dict = field(default_factory=dict)
    rounds: list = field(default_factory=list)
    verified: bool = False
    message: str = ""
    uniform_tried: bool = False


def _generate(
    pl: PlanContext, cons, failing, checks, n_active, max_rounds, kw: Study
) -> PlanResult:
    """The rounds of constraint generation (module docstring), then the energies."""
    st = _Rounds(cons, checks, np.zeros(len(pl.sites)))
    if failing and not pl.brackets:  # no screening to rank by: simulate every failing one
        _add_base(pl, st, failing, kw)
    failing = list(pl.planned(failing))
    while failing and not st.active:  # the first active set, less any N-1 insecure
        st.active = _most_binding(failing, pl.brackets, pl.base, n_active)
        _add_base(pl, st, st.active, kw)
        failing = list(pl.planned(failing))
    if not failing:
        st.verified = True
        st.message = (
            "every contingency is stable without storage"
            if st.cons
            else f"every contingency set aside {_aside_words(pl)}: no storage to place"
            if pl.not_simulable or pl.n1_insecure
            else "no contingency left to plan for: no storage to place"
        )
    else:
        st.message = f"not verified after {max_rounds} round(s) of constraint generation"
    for rnd in range(1, max_rounds + 1 if failing else 1):
        if _round(pl, st, (rnd, max_rounds), n_active, kw):
            break
    else:
        last = st.rounds[-1] if failing and st.rounds else {}
        if last.get("set_aside") or "uniform_start_pct" in last:
            _check_last_allocation(pl, st, max_rounds)
    mwh, energy, ok = size_energy(pl, st.cons, st.mw, st.checks)
    if st.verified and not ok:
        st.verified, st.message = False, st.message + "; the sized energies fail a check run"
    longer = _run_end(pl, st)
    lost = sorted(n for n, r in longer.items() if run_end_lost(r))
    run_end = {
        "window_s": T_AFTER_FAULT,
        "checked": sorted(longer),
        "not_converged": lost,
        "cct_no_storage_not_converged": sorted(
            c.name
            for c in st.cons
            if run_end_lost((pl.base.get(c.name) or {}).get("run_end_check"))
        ),
    }
    if lost:
        st.message += (
            f"; verified in the {T_AFTER_FAULT:g}-s window only: "
            f"{counted(len(lost), 'contingency', 'contingencies')} NOT "
            "CONVERGED IN THE RUN'S END ("
            + ", ".join(lost)
            + f"): cleared at the required time with this allocation, the run "
            f"{T_AFTER_FAULT:g} s longer loses synchronism"
        )
    return PlanResult(
        case=pl.case,
        requirement="",
        load_levels=(),
        sites=pl.sites,
        mw=st.mw,
        mwh=mwh,
        cost=pl.cost.split(pl.sites, st.mw, mwh),
        verified=st.verified,
        contingencies=_rows(st.cons, st.checks, st.evs, pl.base, longer),
        rounds=st.rounds,
        active=[c.name for c in st.active],
        message=st.message,
        energy=energy,
        run_end=run_end,
    )


def _run_end(pl: PlanContext, st: _Rounds) -> dict:
    """The checks whose window the CCT searches put in question, run again T_AFTER_FAULT s
    longer with the allocation (one run each, `PlanContext.check` with longer): those of
    the contingencies stable at their required time whose CCT search without storage,
    or with the allocation, had its unstable end separating late in its run (its
    ``run_end_check`` not None).  Name -> {"t_end_s", "t_separation_s"} (s; None: stable
    there)."""
    flagged = [
        c
        for c in st.cons
        if st.checks.get(c.name, {}).get("stable_at_check")
        and any(
            (ev or {}).get("run_end_check") is not None
            for ev in (pl.base.get(c.name), st.evs.get(c.name))
        )
    ]
    if not flagged:
        return {}
    pl.say(
        f"{counted(len(flagged), 'contingency', 'contingencies')} whose CCT search separated "
        f"late in its {T_AFTER_FAULT:g}-s window: each check run {T_AFTER_FAULT:g} s longer "
        "with the allocation (" + ", ".join(c.name for c in flagged) + ")"
    )
    out = pl.check(flagged, st.mw, longer=True)
    return {n: {k: r[k] for k in RUN_END_KEYS} for n, r in out.items()}


def _aside_words(pl: PlanContext) -> str:
    """How a message names what was set aside before the rounds: as not simulable, as
    N-1 insecure (each with its names)."""
    words = [
        f"as {label} ({', '.join(names)})"
        for label, names in (
            ("not simulable", pl.not_simulable),
            ("N-1 insecure", pl.n1_insecure),
        )
        if names
    ]
    return " and ".join(words)


def _add_base(pl: PlanContext, st: _Rounds, cons, kw: Study) -> None:
    """`PlanContext.add_base` of cons, then those set aside as N-1 insecure left out of
    the rounds' contingencies and active set."""
    pl.add_base(cons, pl.brackets, kw)
    st.cons = pl.planned(st.cons)
    st.active = list(pl.planned(st.active))


def _round(pl: PlanContext, st: _Rounds, of: tuple, n_active: int, kw: Study) -> bool:
    """Round rnd of at most `of` = (rnd, max_rounds): the verified loop (`place`) for the
    active set, priced with the energy per MW of the latest checks, then every
    contingency checked at its allocation.  A contingency proven infeasible is set aside
    when the plan drops them.  Returns whether constraint generation ends (st.verified
    and st.message say how).  Its first line bounds what is left (rounds, iterations: a
    plan's progress named each batch's jobs only, no plan's whole)."""
    rnd, max_rounds = of
    pl.energy_rate = mwh_per_mw(len(pl.sites), st.checks)
    sites = pl.priced(pl.energy_rate)
    pl.say(
        f"round {rnd} of at most {max_rounds}: solving for "
        f"{counted(len(st.active), 'contingency', 'contingencies')} ("
        + ", ".join(c.name for c in st.active)
        + f"), in at most {counted(pl.place.max_iter, 'iteration')}"
    )
    try:
        res = place(
            pl.case,
            st.active,
            replace(kw, sites=sites),
            replace(pl.place, site_cost=pl.site_costs),
            WarmStart(
                base={c.name: pl.base[c.name] for c in st.active},
                start=None if not st.mw.any() else st.mw,
                evaluations=st.evs,
            ),
            progress=lambda m: pl.say(f"round {rnd}: {m}"),
        )
    except InfeasibleError as exc:
        if not pl.drop_infeasible or not exc.contingencies:
            raise
        _set_aside(pl, st, rnd, exc)
        return False if st.active else _recheck(pl, st, rnd, n_active, kw)
    return _add_failing(pl, st, rnd, res, kw)


def _set_aside(pl: PlanContext, st: _Rounds, rnd: int, exc: InfeasibleError) -> None:
    """Set aside the contingencies exc proves infeasible (listed in the plan and in this
    round's record), out of every later round."""
    gone = set(exc.contingencies)
    pl.infeasible.append(str(exc))
    pl.set_aside.extend(sorted(gone))
    st.rounds.append(
        {
            "round": rnd,
            "active": [c.name for c in st.active],
            "total_mw": None,
            "set_aside": sorted(gone),
            "failing": [],
            "iterations": 0,
        }
    )
    pl.say(f"round {rnd}: set aside as infeasible: {', '.join(sorted(gone))}")
    st.cons = tuple(c for c in st.cons if c.name not in gone)
    st.active = [c for c in st.active if c.name not in gone]
    st.evs = {k: v for k, v in st.evs.items() if k not in gone}


def _check_last_allocation(pl: PlanContext, st: _Rounds, rounds: int) -> None:
    """The last round ended with an allocation its checks have not seen: it set
    contingencies aside (the allocation it started from may meet those left: ACTIVSg2000's
    ten faults at three loads and the uniform 0.5 % fleet, once the last that failed its
    check was set aside), or it found the least uniform fleet (`_uniform_start`).  Checked
    on every contingency left (one run each; the energies are sized from these runs), and
    verified when each is stable cleared at its required time there and each of the active
    set meets its target by its CCT there (the evaluations at that allocation)."""
    fails = _check_all(pl, st)
    short = [c for c in st.active if _short_of_target(c, st.evs)]
    pl.say(
        f"after round {rounds}: {st.mw.sum():.1f} MW, checked "
        f"{counted(len(st.cons), 'contingency', 'contingencies')}: "
        + (f"{len(fails)} fail" if fails else "all stable")
        + (f", {len(short)} of the active set short of its CCT target" if short else "")
    )
    if not fails and not short:
        st.verified = True
        st.message = (
            f"verified on every contingency after {rounds} round(s), at the allocation "
            "the last round left"
        )


def _check_all(pl: PlanContext, st: _Rounds) -> list:
    """Every contingency checked at the allocation (one run each, into st.checks): those
    unstable cleared at their required time."""
    st.checks = pl.check(st.cons, st.mw)
    return [c for c in st.cons if not st.checks[c.name]["stable_at_check"]]


def _short_of_target(c, evs: dict) -> bool:
    """Whether contingency c's CCT in the evaluations evs (name -> evaluation at one
    allocation) is missing or below its target."""
    cct = (evs.get(c.name) or {}).get("cct_s")
    return not c.met_by(cct)


def _recheck(pl: PlanContext, st: _Rounds, rnd: int, n_active: int, kw) -> bool:
    """Nothing left to solve for: every contingency checked at the allocation; the most
    binding of those that fail are the next active set.  Returns whether none fails."""
    if not st.cons:
        st.mw, st.verified = np.zeros_like(st.mw), True
        aside = [f"as infeasible ({', '.join(pl.set_aside)})"] if pl.set_aside else []
        if pl.not_simulable or pl.n1_insecure:
            aside.append(_aside_words(pl))
        st.message = (
            f"every contingency set aside {' and '.join(aside)}: no storage to place"
            if aside
            else "no contingency left to plan for: no storage to place"
        )
        return True
    fails = _check_all(pl, st)
    if not fails:
        st.verified, st.message = True, f"verified on every contingency after {rnd} round(s)"
        return True
    st.active = _most_binding(fails, pl.brackets, pl.base, n_active)
    _add_base(pl, st, st.active, kw)
    if not st.active:  # every one that failed was N-1 insecure, now set aside
        return _recheck(pl, st, rnd, n_active, kw)
    return False


def _add_failing(pl: PlanContext, st: _Rounds, rnd: int, res, kw) -> bool:
    """The loop's allocation (res, `stabctl.placement.loop.PlacementResult`) checked at
    every contingency; those that fail join the active set.  Returns whether constraint
    generation ends: verified (none fails), or not (the loop did not verify, or only
    active contingencies fail)."""
    st.mw, st.evs = res.allocation.mw, dict(res.evaluations)
    fails = _check_all(pl, st)
    st.rounds.append(
        {
            "round": rnd,
            "active": [c.name for c in st.active],
            "total_mw": total_mw(st.mw),
            "loop_verified": res.verified,
            "loop_message": res.message,
            "failing": [c.name for c in fails],
            "iterations": len(res.iterations),
        }
    )
    pl.say(
        f"round {rnd}: {st.mw.sum():.1f} MW, checked "
        f"{counted(len(st.cons), 'contingency', 'contingencies')}: "
        + (
            f"{len(fails)} fail (" + ", ".join(c.name for c in fails[:8]) + ")"
            if fails
            else "all stable"
        )
    )
    if not res.verified:
        if _uniform_start(pl, st, rnd, kw):
            return False
        st.message = f"round {rnd}: the loop did not verify an allocation ({res.message})"
        return True
    if not fails:
        st.verified, st.message = True, f"verified on every contingency after {rnd} round(s)"
        return True
    new = [c for c in fails if c.name not in {a.name for a in st.active}]
    if not new:
        st.message = (
            f"round {rnd}: contingencies of the active set fail their check run: "
            f"{', '.join(c.name for c in fails)}"
        )
        return True
    st.active = st.active + new
    _add_base(pl, st, new, kw)
    return False


def _uniform_start(pl: PlanContext, st: _Rounds, rnd: int, kw: Study) -> bool:
    """Once per plan, when a round's loop verified no allocation: the least uniform fleet
    meeting the active set (`references.least_pct`, the same % of MVA at every site, by
    its check runs) and the active set's CCTs there; when they meet every target, the
    next round starts from it (the loop then returns nothing costlier, docs/placement.md
    section 4).  The loop's linearisations can miss an allocation the paper's law needs
    far from where it starts (WECC-179's 75-77: 0.228-0.256 s at every allocation up to
    3.6 GW on 15 sites, 0.255 s without storage, 0.421 s with every site at its bound).
    Returns whether the next round starts there."""
    if st.uniform_tried:
        return False
    st.uniform_tried = True
    fleet, pct_max = uniform_fleet(pl)
    pct = least_pct(pl, st.active, fleet, pct_max)
    if pct is None:
        pl.say(f"round {rnd}: no uniform fleet up to {pct_max:g} % meets the active set")
        return False
    mw = fleet(pct)
    evs = evaluations(pl.case, st.active, mw, kw, VerifyOptions(base=pl.base))
    if any(_short_of_target(c, evs) for c in st.active):
        pl.say(f"round {rnd}: the uniform fleet of {pct:g} % misses a target by its CCT")
        return False
    pl.say(
        f"round {rnd}: the uniform fleet of {pct:g} % ({mw.sum():.1f} MW) meets the "
        "active set: the next round starts there"
    )
    st.mw, st.evs = mw, evs
    st.rounds[-1]["uniform_start_pct"] = pct
    return True


def _rows(cons, checks, evs, base, longer=None) -> list:
    """One row per contingency: name, fault, load, required time, stable at it, CCT
    without storage (and whether it is only known above t_max) and with the allocation
    where simulated, margin (s); from its run at the required time with the allocation,
    the devices' switchings and those chattering, and the machines the law was armed on
    (``place --coi critical``; None otherwise or without such a run); the run's end
    checks (`CCTResult.run_end_check` of each CCT search, and its check run
    T_AFTER_FAULT s longer, `_run_end`: longer, name -> {"t_end_s", "t_separation_s"};
    None: not in question, not run); the islanding of its search without storage
    (``islanded``: buses cut from every machine, their load shed, or machines lost with
    their island; the CCT is the rest of the system's)."""
    longer = longer or {}
    out = []
    for c in cons:
        cct = evs.get(c.name, {}).get("cct_s")
        out.append(
            {
                "name": c.name,
                "fault": c.fault.describe(),
                "fault_name": c.fault_name,
                "load": c.load,
                "required_s": c.target_cct_s,
                "met": bool(checks[c.name]["stable_at_check"]) and (cct is None or c.met_by(cct)),
                "cct_no_storage_s": base.get(c.name, {}).get("cct_s"),
                # stable without storage cleared at t_max: its CCT only known above it
                "cct_no_storage_above_t_max": bool(base.get(c.name, {}).get("above_t_max")),
                "cct_s": cct,
                "margin_s": None if cct is None else cct - c.target_cct_s,
                "margin_at_least": False,
                # its run at the required time with the allocation (None: not run)
                "switchings": checks[c.name].get("switchings"),
                "chattering": checks[c.name].get("chattering"),
                "critical_group": checks[c.name].get("critical_group"),
                "cct_no_storage_run_end_check": base.get(c.name, {}).get("run_end_check"),
                "cct_run_end_check": evs.get(c.name, {}).get("run_end_check"),
                "run_end_check": longer.get(c.name),
                # what the fault's trip cuts off (its search without storage; round 59
                # BC03: a trip losing a machine was "met" without a word)
                "islanded": base.get(c.name, {}).get("islanded") or [],
            }
        )
    return out
