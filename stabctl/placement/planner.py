"""A planner's placement: least-cost ESD sites, MW and MWh such that every screened fault
is stable when cleared at its required clearing time, at every load level planned for
(docs/placement.md, section 7).

Requirements (`Requirement`, any mix, the strictest wins): a required clearing time in
cycles (every contingency stable when cleared after N cycles, in the spirit of NERC
TPL-001: normal clearing plus a margin), a CCT gain over the CCT without storage (%), or
an absolute CCT (s); per-contingency overrides (`read_requirements`).  A contingency is a
fault at one load level (`Contingency.load`, `stabctl.network.powerflow.scale_load`).

Verification (`check`): a contingency is met at an allocation when the run cleared at its
required clearing time is stable; the contingencies the program is solved for (the active
set) are moreover met by their first unstable clearing time (`stabctl.placement.loop`).

Constraint generation (`plan`): every contingency is first simulated once without storage,
cleared at its required time; those that fail are the candidates, the most binding of
them (smallest CCT without storage relative to the requirement, up to `n_active`) the
first active set.  Each round solves the verified trust-region loop
(`stabctl.placement.loop.place`) for the active set, warm-started from the last
allocation with the evaluations already simulated, then checks every contingency at the
allocation (one run each) and adds those that fail; it ends when none fails.

Sizing and cost (`CostModel`): cost = sum_j (c_mw,j MW_j + c_mwh,j MWh_j + c_site,j [MW_j
> 0]).  The energy of each device comes from the verifying runs: its state of charge along
every run cleared at the required time (integrated by the simulator between located
switchings, `SimulationResult.meta["storage"]`), the largest excursion over the
contingencies, doubled (a device started half full) with
ENERGY_MARGIN; the runs that set each device's energy are then simulated again with that
finite energy (`check`).  Inside the program the energy is priced per MW: at each site
the excursion per MW of its bang-bang modes along the latest runs (also where no device is
installed yet).

References (`least_uniform`, `alone`): the least uniform fleet (the same % of MVA at every
generator, bisection on the %) meeting the same requirements, and each fault's own least
allocation.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from stabctl.dynamics.options import ModelOptions
from stabctl.errors import InputError
from stabctl.placement.evaluation import (Contingency, _fault_dict, check, controller_dict,
                                          devices_of)
from stabctl.placement.loop import (DEFAULT_CONTROLLER, _as_allocation, _pool, _rounded,
                                    evaluations, place)
from stabctl.placement.program import InfeasibleError, candidate_sites

#: Relative margin on the sized energy (the simulator integrates the state of charge
#: within its steps, the sizing on the recorded grid).
ENERGY_MARGIN = 0.05
#: Longest silence of the progress callback during a batch of runs (s).
HEARTBEAT_S = 8.0
#: Uniform fleet bisection: resolution (% of MVA).
UNIFORM_RES_PCT = 0.1


# -- requirements and costs ------------------------------------------------------------------

@dataclass(frozen=True)
class Requirement:
    """What a contingency must withstand; any mix of the three, the strictest wins.

    Attributes
    ----------
    cycles : float or None
        Required clearing time, cycles of the case frequency: stable when cleared then.
    gain_pct : float or None
        CCT raised by this % over the CCT without storage.
    cct_s : float or None
        Required CCT, s.

    Raises
    ------
    InputError
        None given, or one not > 0.
    """

    cycles: float | None = None
    gain_pct: float | None = None
    cct_s: float | None = None

    def __post_init__(self):
        given = [v for v in (self.cycles, self.gain_pct, self.cct_s) if v is not None]
        if not given:
            raise InputError("no requirement given: need a required clearing time "
                             "(cycles), a CCT gain (%) or a target CCT (s)")
        if not all(np.isfinite(v) and v > 0 for v in given):
            raise InputError(f"requirements must be > 0, got cycles={self.cycles}, "
                             f"gain={self.gain_pct} %, cct={self.cct_s} s")

    @property
    def needs_base(self) -> bool:
        """Whether the target depends on the CCT without storage (a gain)."""
        return self.gain_pct is not None

    def target_s(self, freq_hz: float, tol: float, base_cct_s: float | None = None) -> float:
        """The required clearing time (s), rounded up to the tolerance lattice.

        Parameters
        ----------
        freq_hz : float
            Case frequency, Hz.
        tol : float
            CCT tolerance, s.
        base_cct_s : float or None
            CCT without storage, s (needed with a gain).

        Raises
        ------
        InputError
            A gain without base_cct_s.
        """
        t = []
        if self.cycles is not None:
            t.append(self.cycles / freq_hz)
        if self.cct_s is not None:
            t.append(self.cct_s)
        if self.gain_pct is not None:
            if base_cct_s is None:
                raise InputError("a CCT gain needs the CCT without storage")
            t.append(base_cct_s * (1 + self.gain_pct / 100))
        return round(float(np.ceil(max(t) / tol - 1e-6)) * tol, 12)

    def describe(self) -> str:
        """E.g. ``"5 cycles"``, ``"CCT +10 %"``."""
        parts = ([f"{self.cycles:g} cycles"] if self.cycles is not None else []) + \
            ([f"CCT +{self.gain_pct:g} %"] if self.gain_pct is not None else []) + \
            ([f"CCT {1000 * self.cct_s:g} ms"] if self.cct_s is not None else [])
        return ", ".join(parts)


def read_requirements(path) -> dict:
    """Per-fault requirement overrides from a fault list CSV (`stabctl.stability.cct.
    read_faults`'s columns plus any of ``required_clearing_cycles``,
    ``target_cct_gain``, ``target_cct_s``; a row with none keeps the global one).

    Returns
    -------
    dict
        Fault name (`Contingency.fault_name`, e.g. ``"83-33"``) -> `Requirement`.

    Raises
    ------
    InputError
        Unreadable file or a value that is not a number > 0 (naming the line).
    """
    from stabctl.stability.cct import csv_rows, read_faults

    path = Path(path)
    faults = read_faults(path)
    rows = csv_rows(path, "fault list", ("bus", "far_bus"))
    out = {}
    for line, (fault, row) in enumerate(zip(faults, rows), start=2):
        vals = {k: (row.get(c) or "").strip() for k, c in
                (("cycles", "required_clearing_cycles"), ("gain_pct", "target_cct_gain"),
                 ("cct_s", "target_cct_s"))}
        if not any(vals.values()):
            continue
        try:
            req = Requirement(**{k: float(v) if v else None for k, v in vals.items()})
        except (ValueError, InputError) as exc:
            raise InputError(f"fault list {path} line {line}: {exc}") from None
        out[Contingency(fault, 1.0).fault_name] = req
    return out


@dataclass(frozen=True)
class CostModel:
    """Cost of an ESD: per MW, per MWh of usable energy and per site (any currency).

    Attributes
    ----------
    per_mw, per_mwh, per_site : float
        Defaults for every site (>= 0; per_mw + per_mwh > 0).
    overrides : dict
        Machine number -> {"per_mw", "per_mwh", "per_site"} (any subset) for its site.

    Raises
    ------
    InputError
        A negative cost, or no cost per MW nor per MWh.
    """

    per_mw: float = 1.0
    per_mwh: float = 0.0
    per_site: float = 0.0
    overrides: dict = field(default_factory=dict)

    def __post_init__(self):
        for k, o in [(None, {"per_mw": self.per_mw, "per_mwh": self.per_mwh,
                             "per_site": self.per_site}), *self.overrides.items()]:
            if any(not (np.isfinite(v) and v >= 0) for v in o.values()):
                where = "" if k is None else f" (site of G{k})"
                raise InputError(f"costs must be numbers >= 0{where}, got {o}")
        if not self.per_mw + self.per_mwh > 0:
            raise InputError("need a cost per MW or per MWh > 0")

    def of(self, machine: int) -> tuple[float, float, float]:
        """(per MW, per MWh, per site) at the site of `machine`."""
        o = self.overrides.get(int(machine), {})
        return (o.get("per_mw", self.per_mw), o.get("per_mwh", self.per_mwh),
                o.get("per_site", self.per_site))

    def split(self, sites, mw, mwh) -> dict:
        """{"mw", "mwh", "site", "total"} cost of ratings mw and energies mwh per site."""
        c = np.array([self.of(s.machine) for s in sites]).reshape(len(sites), 3)
        mw, mwh = np.asarray(mw, float), np.asarray(mwh, float)
        out = {"mw": float(c[:, 0] @ mw), "mwh": float(c[:, 1] @ mwh),
               "site": float(c[:, 2] @ (mw > 0))}
        out["total"] = out["mw"] + out["mwh"] + out["site"]
        return out


def read_site_costs(path) -> dict:
    """Per-site cost overrides from a CSV with a ``machine`` column and any of
    ``cost_mw``, ``cost_mwh``, ``cost_site``: machine -> {"per_mw", ...}.  Raises
    InputError naming the line."""
    from stabctl.stability.cct import csv_rows

    rows = csv_rows(path, "site costs", ("machine",), " and any of cost_mw,cost_mwh,cost_site")
    out = {}
    for line, row in enumerate(rows, start=2):
        try:
            out[int(row["machine"])] = {k: float(row[c]) for k, c in
                                        (("per_mw", "cost_mw"), ("per_mwh", "cost_mwh"),
                                         ("per_site", "cost_site")) if (row.get(c) or "").strip()}
        except (TypeError, ValueError) as exc:
            raise InputError(f"site costs {path} line {line}: {exc}") from None
    return out


def screening_brackets(path) -> dict:
    """The [stable, unstable] clearing times without storage (s) of every fault a
    screening (`stabctl screen --out`, or a placement study's records) bracketed: fault
    name (`Contingency.fault_name`) -> (t_stable, t_unstable), for `plan`'s `brackets`; a
    fault still stable at the screening's limit t_max: (t_max, None).  Records with
    storage or with another outcome are skipped.  Raises InputError for a file that is not
    sweep records."""
    from stabctl.parallel import read_records
    from stabctl.stability.cct import LineFault

    try:
        records = read_records(path)
    except (OSError, ValueError) as exc:
        raise InputError(f"screening records {path}: {exc}") from None
    out = {}
    for rec in records.values():
        r, inputs = rec.get("result") or {}, rec.get("inputs") or {}
        still = "still stable" in (rec.get("error") or "") and "t_max" in inputs
        if inputs.get("esd_pct") is not None or not (
                (rec.get("status") == "ok" and "t_stable_s" in r) or still):
            continue
        f = r.get("fault") or inputs
        fault = LineFault(int(f["bus"]), None if f["far_bus"] is None else int(f["far_bus"]),
                          float(f["t_fault"]), int(f["circuit"]),
                          tuple((int(a), int(b)) for a, b in f["trips"]))
        out[Contingency(fault, 1.0).fault_name] = \
            (float(inputs["t_max"]), None) if still else (r["t_stable_s"], r["t_unstable_s"])
    return out


# -- the result --------------------------------------------------------------------------------

@dataclass
class PlanResult:
    """Outcome of `plan`.

    sites: candidate sites; mw, mwh: rating (MW) and usable energy (MWh) per site
    (n_sites,); cost: `CostModel.split`; verified: every contingency checked stable at its
    required clearing time (and the active ones by their CCT, and the sized energies);
    contingencies: one row per contingency (`rows`); rounds: one dict per round of
    constraint generation; active: names of the contingencies the program was solved
    for; message: why it stopped; n_simulations: runs simulated in all; wall_time_s.
    uniform, alone: the references when asked (`least_uniform`, `alone`); half_step: the
    tightest contingencies again at half the step (`half_step`) when asked; out_of_scope:
    contingencies unstable when cleared at once; infeasible, set_aside: the proofs and
    names of those set aside as infeasible.
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
        return {"verified": self.verified, "message": self.message,
                "requirement": self.requirement, "load_levels": list(self.load_levels),
                "allocation": self.allocation(), "total_mw": self.total_mw,
                "total_mwh": float(self.mwh.sum()), "n_sites": int(np.count_nonzero(self.mw)),
                "cost": self.cost, "n_contingencies": len(self.contingencies),
                "n_met": len(met), "active": self.active,
                "out_of_scope": self.out_of_scope, "infeasible": self.infeasible,
                "set_aside": self.set_aside,
                "contingencies": self.contingencies, "rounds": self.rounds,
                "n_simulations": self.n_simulations, "wall_time_s": self.wall_time_s,
                "uniform": self.uniform, "alone": self.alone, "half_step": self.half_step}


# -- the planner -------------------------------------------------------------------------------

@dataclass
class _Plan:
    """What every round needs."""

    case: str
    sites: tuple
    cost: CostModel
    controller: object
    model: dict
    run_map: object
    tol: float
    t_max: float
    say: object
    n_runs: int = 0
    base: dict = field(default_factory=dict)
    energy_rate: np.ndarray | None = None
    drop_infeasible: bool = False
    brackets: dict | None = None
    infeasible: list = field(default_factory=list)
    set_aside: list = field(default_factory=list)
    loop_kw: dict = field(default_factory=dict)
    lock: object = field(default_factory=threading.Lock)

    def check(self, contingencies, mw, energy_mj=None, h: float | None = None) -> dict:
        """`check` of every contingency at ratings mw (one run each, in parallel): name ->
        check dict.  energy_mj: usable energy per site (MJ) of finite devices; h: another
        integration step (s) than the plan's."""
        devs = devices_of(self.sites, mw)
        if energy_mj is not None:
            used = [j for j, p in enumerate(mw) if p > 0]
            devs = [d + [float(energy_mj[j])] for d, j in zip(devs, used)]
        ctrl = controller_dict(self.controller)
        sites = [[s.bus, s.machine] for s in self.sites]
        jobs = [{"case": self.case, "fault": _fault_dict(c.fault), "devices": devs,
                 "sites": sites, "controller": ctrl, "t_clear": c.target_cct_s,
                 "load": c.load, **self.model, **({} if h is None else {"h": h})}
                for c in contingencies]
        return dict(zip((c.name for c in contingencies), self.run_map(check, jobs)))

    def mwh_per_mw(self, checks) -> np.ndarray:
        """Usable energy per MW at each site (MWh/MW): twice the largest state-of-charge
        excursion per MW of its modes over the runs `checks`."""
        exc = np.zeros(len(self.sites))
        for ck in checks.values():
            if ck["site_excursion_s"]:
                exc = np.maximum(exc, ck["site_excursion_s"])
        return (1 + ENERGY_MARGIN) * 2 * exc / 3600.0

    def priced(self, mwh_per_mw) -> tuple:
        """Sites whose cost per MW includes their energy at mwh_per_mw (MWh/MW)."""
        return tuple(replace(s, cost=max(self.cost.of(s.machine)[0]
                                         + self.cost.of(s.machine)[1] * e, 1e-9))
                     for s, e in zip(self.sites, mwh_per_mw))

    def counting(self, run_map, beat):
        """run_map that adds the simulations its jobs report to n_runs (and tells the
        heartbeat `beat`)."""
        def counted(func, jobs):
            beat.note(f"{len(jobs)} {func.__name__} job(s) running, {self.n_runs} runs "
                      "simulated before them")
            out = run_map(func, jobs)
            with self.lock:         # `_alone` runs batches from several threads
                self.n_runs += sum(o.get("n_simulations") or 0 for o in out)
            return out
        return counted

    @property
    def site_costs(self) -> np.ndarray:
        return np.array([self.cost.of(s.machine)[2] for s in self.sites])


def contingencies_of(faults, requirement: Requirement, freq_hz: float, tol: float,
                     load_levels=(1.0,), overrides: dict | None = None,
                     base: dict | None = None) -> tuple:
    """One `Contingency` per fault and load level with its required clearing time (s):
    the fault's override (by fault name) or `requirement`; base (name -> evaluation
    without storage) for gain requirements.  Raises InputError (a gain without base)."""
    overrides = overrides or {}
    out = []
    for f in faults:
        name = Contingency(f, 1.0).fault_name
        req = overrides.get(name, requirement)
        for load in load_levels:
            c = Contingency(f, 1.0, float(load))
            b = None if base is None or c.name not in base else base[c.name]["cct_s"]
            out.append(replace(c, target_cct_s=req.target_s(freq_hz, tol, b)))
    return tuple(out)


def plan(case: str, faults, requirement: Requirement, *, load_levels=(1.0,),
         overrides: dict | None = None, cost: CostModel | None = None, sites=None,
         brackets: dict | None = None, n_active: int = 12, max_rounds: int = 6,
         max_iter: int = 6, tol: float = 1e-3, t_max: float = 1.0, workers: int = 1,
         scheduler: str | None = None, controller=None, conventions: str = "ieee",
         h: float | None = None, run_map=None, progress=None, uniform: bool = False,
         alone: bool = False, margins_tol: float | None = None, margins_cap_s: float = 0.1,
         scope_stable_at_once: bool = True, drop_infeasible: bool = False,
         half_step_n: int = 0, **loop_kw) -> PlanResult:
    """Least-cost ESD sites, MW and MWh meeting `requirement` on every fault at every load
    level, verified by simulation (module docstring).

    Parameters
    ----------
    case : str
        Built-in case name or case file (workers load it by name).
    faults : sequence of LineFault
        Every contingency to meet (e.g. a whole screening).
    requirement : Requirement
        Global requirement; overrides: fault name -> Requirement (`read_requirements`).
    load_levels : sequence of float, optional
        Load levels (fractions of the base load) every fault is verified at; default (1,).
    cost : CostModel or None, optional
        Costs (default 1 per MW: least MW).
    sites : sequence of Site or None, optional
        Candidates (default `candidate_sites`: every generator's HV bus, up to 50 % of
        its MVA).
    brackets : dict or None, optional
        Fault name -> [stable, unstable] clearing times without storage at the base load
        (s), e.g. a screening's, where the CCT searches start; [t, None]: still stable
        when cleared at t (a screening's limit), known stable at any requirement up to t.
    n_active : int, optional
        Contingencies in the first active set (the most binding of those unstable
        without storage); default 12.
    max_rounds : int, optional
        Rounds of constraint generation at most; max_iter: allocations simulated per
        round at most (`place`).
    tol, t_max : float, optional
        CCT tolerance and search limit, s.
    workers, scheduler, run_map, controller, conventions, h
        As `stabctl.placement.loop.place`.
    progress : callable(str) or None
        One line per step.
    uniform, alone : bool, optional
        Also the least uniform fleet (`least_uniform`) and each fault's own least
        allocation (`alone`) meeting the same requirements.
    scope_stable_at_once : bool, optional
        Leave out (and list in `PlanResult.out_of_scope`) the contingencies unstable
        already when cleared at once (the line trip alone, at their load level), which no
        required clearing time can describe; default True.  False: they stay in, and
        are infeasible unless storage makes the trip alone stable.
    drop_infeasible : bool, optional
        A contingency proven infeasible (named by `InfeasibleError`) is set aside, listed
        in `PlanResult.infeasible`, and the others are planned for; default False: the
        error is raised.
    margins_tol, margins_cap_s : float or None, float, optional
        Also the clearing margin with the allocation of every contingency the program
        was not solved for, to margins_tol (s), up to margins_cap_s (s; `margins`);
        None: those are only checked at their required time (margin >= 0 known).
    half_step_n : int, optional
        Also simulate the half_step_n contingencies of least clearing margin again at
        half the integration step (`half_step`); default 0: not done.
    **loop_kw
        zeta_min, amplitude_hz, max_sites: passed to every `place` (the damping is
        verified by the loop, for the allocation as a whole).

    Returns
    -------
    PlanResult

    Raises
    ------
    InfeasibleError
        A contingency misses its requirement even with every site at its bound (named
        with its load level).
    InputError
        No faults, bad settings, a fault unstable already when cleared at once.
    PowerFlowError, CaseError
        A load level without a power flow or a valid initial state (named).
    """
    wall = time.perf_counter()
    faults = list(faults)
    if not faults:
        raise InputError("no contingency given")
    if n_active < 1 or max_rounds < 1 or max_iter < 1:
        raise InputError("need n_active, max_rounds and max_iter >= 1")
    levels = tuple(dict.fromkeys(float(x) for x in load_levels))
    if not levels or any(not (np.isfinite(x) and x > 0) for x in levels):
        raise InputError(f"load levels must be numbers > 0, got {list(load_levels)}")
    from stabctl.stability.cct import cached_simulator

    for x in levels:            # a load level without a power flow fails here, named
        cached_simulator(case, ModelOptions(conventions, h), load=x)
    sim = cached_simulator(case, ModelOptions(conventions, h))
    sites = tuple(sites or candidate_sites(sim.case))
    cost = cost or CostModel()
    with _pool(run_map, workers, scheduler) as pool_map, _Heartbeat(progress) as say:
        pl = _Plan(case, sites, cost, controller or DEFAULT_CONTROLLER,
                   {"conventions": conventions, "h": h}, None, tol, t_max, say,
                   loop_kw=loop_kw, drop_infeasible=drop_infeasible, brackets=brackets)
        rm = pl.run_map = pl.counting(pool_map, say)
        kw = {"sites": sites, "tol": tol, "t_max": t_max, "run_map": rm,
              "controller": pl.controller, "conventions": conventions, "h": h}
        base = pl.base
        if requirement.needs_base or any(r.needs_base for r in (overrides or {}).values()):
            every = contingencies_of(faults, Requirement(cct_s=t_max), sim.case.freq_hz, tol,
                                     levels)
            say(f"CCT without storage of {len(every)} contingencies")
            base.update(_base(pl, every, brackets, kw))
        cons = contingencies_of(faults, requirement, sim.case.freq_hz, tol, levels,
                                overrides, base)
        known = _stable_by_screening(cons, brackets)
        say(f"{len(cons)} contingencies ({len(faults)} faults x {len(levels)} load "
            f"level(s)): each cleared at its required time without storage ({len(known)} "
            "known stable there from the screening)")
        checks = pl.check([c for c in cons if c.name not in known], np.zeros(len(sites)))
        failing = [c for c in cons if c.name in checks and
                   not checks[c.name]["stable_at_check"]]
        out = _out_of_scope(pl, failing) if scope_stable_at_once else set()
        if out:
            say("out of scope (unstable even when cleared at once, the line trip alone): "
                + ", ".join(sorted(out)))
        cons = tuple(c for c in cons if c.name not in out)
        failing = [c for c in failing if c.name not in out]
        checks = {**{n: _STABLE for n in known}, **checks}
        say(f"{len(failing)} of {len(cons)} unstable without storage: "
            + ", ".join(c.name for c in failing[:12]) + (" ..." if len(failing) > 12 else ""))
        result = _generate(pl, cons, failing, checks, base, brackets, n_active, max_rounds,
                           max_iter, kw)
        result.out_of_scope = sorted(out)
        result.infeasible = list(pl.infeasible)
        result.set_aside = list(pl.set_aside)
        kept = {r["name"] for r in result.contingencies}
        cons = tuple(c for c in cons if c.name in kept)
        failing = [c for c in failing if c.name in kept]
        result.requirement = _describe(requirement, overrides)
        result.load_levels = levels
        _references(pl, cons, failing, result, kw, margins_tol, margins_cap_s, half_step_n,
                    uniform, alone, max_iter)
    result.n_simulations = pl.n_runs
    result.wall_time_s = time.perf_counter() - wall
    return result


def _references(pl: _Plan, cons, failing, result: PlanResult, kw, margins_tol,
                margins_cap_s, half_step_n, uniform, alone, max_iter) -> None:
    """What `plan` adds to a result when asked: the clearing margins (then the half-step
    check, which ranks by them), the least uniform fleet and each binding fault alone.
    They are independent, so they run at the same time (one thread each, sharing the
    worker pool: fewer idle workers at the end of each one's batches)."""
    from concurrent.futures import ThreadPoolExecutor

    def margins_and_half_step():
        if margins_tol is not None:
            margins(pl, cons, result, margins_tol, margins_cap_s, kw)
        if half_step_n > 0 and result.verified:
            result.half_step = half_step(pl, cons, result, half_step_n, kw)

    with ThreadPoolExecutor(max_workers=3) as threads:
        m = threads.submit(margins_and_half_step)
        u = threads.submit(least_uniform, pl, cons, failing, kw) if uniform else None
        a = threads.submit(_alone, pl, cons, result, max_iter, kw) if alone else None
        m.result()
        result.uniform = None if u is None else u.result()
        result.alone = [] if a is None else a.result()


#: A check known without a run (stable, no energy figures).
_STABLE = {"stable_at_check": True, "energy_mj": [], "site_excursion_s": [], "check_s": None}


def _stable_by_screening(cons, brackets) -> set:
    """Names of base-load contingencies the screening found stable when cleared at their
    required time or later without storage (its stable end is at least the requirement).
    """
    return {c.name for c in cons if brackets and c.load == 1.0 and c.fault_name in brackets
            and brackets[c.fault_name][0] is not None
            and brackets[c.fault_name][0] >= c.target_cct_s - 1e-9}


def _out_of_scope(pl: _Plan, failing) -> set:
    """Names of the contingencies of `failing` unstable without storage even when cleared
    at once (one run each, the line trip alone)."""
    if not failing:
        return set()
    at_once = pl.check([replace(c, target_cct_s=0.0) for c in failing],
                       np.zeros(len(pl.sites)))
    return {n for n, ck in at_once.items() if not ck["stable_at_check"]}


def _describe(requirement: Requirement, overrides) -> str:
    extra = f" ({len(overrides)} fault(s) with their own)" if overrides else ""
    return requirement.describe() + extra


def _base(pl: _Plan, cons, brackets, kw) -> dict:
    """Evaluations without storage (CCT by bisection, from the screening's bracket when
    known, and its gradient) of `cons`, counted."""
    if not cons:
        return {}
    br = {c.name: tuple(brackets[c.fault_name]) for c in cons
          if brackets and c.load == 1.0 and c.fault_name in brackets
          and None not in brackets[c.fault_name]}
    return evaluations(pl.case, cons, None, brackets=br, **kw)


def _most_binding(failing, brackets, base: dict, n: int) -> list:
    """The n contingencies of `failing` with the least ratio of the CCT without storage to
    the requirement: simulated (base) or else the screening's (base load; none: last),
    the heavier load level first among equals.  With a screening no run is needed: the
    CCTs without storage of the rest are simulated only if they are added."""
    def severity(c):
        cct = base[c.name]["cct_s"] if c.name in base else \
            (brackets or {}).get(c.fault_name, (None,))[0]
        return (np.inf if cct is None else cct / c.target_cct_s, -c.load, c.name)

    return sorted(failing, key=severity)[:n]


def _generate(pl: _Plan, cons, failing, checks0, base, brackets, n_active, max_rounds,
              max_iter, kw) -> PlanResult:
    """The rounds of constraint generation (module docstring)."""
    n = len(pl.sites)
    mw = np.zeros(n)
    checks = checks0
    evs, active, rounds = {}, [], []
    verified, message = not failing, "every contingency is stable without storage"
    if failing:
        if not brackets:            # no screening to rank by: simulate every failing one
            base.update(_base(pl, [c for c in failing if c.name not in base], None, kw))
        active = _most_binding(failing, brackets, base, n_active)
        base.update(_base(pl, [c for c in active if c.name not in base], brackets, kw))
        message = f"not verified after {max_rounds} round(s) of constraint generation"
    for rnd in range(1, max_rounds + 1 if failing else 1):
        pl.energy_rate = pl.mwh_per_mw(checks)
        sites = pl.priced(pl.energy_rate)
        pl.say(f"round {rnd}: solving for {len(active)} contingencies ("
               + ", ".join(c.name for c in active) + ")")
        try:
            res = place(pl.case, active, site_cost=pl.site_costs, max_iter=max_iter,
                        base={c.name: base[c.name] for c in active},
                        start=None if not mw.any() else mw, start_evaluations=evs,
                        progress=lambda m, r=rnd: pl.say(f"round {r}: {m}"),
                        **{**kw, **pl.loop_kw, "sites": sites})
        except InfeasibleError as exc:
            if not pl.drop_infeasible or not exc.contingencies:
                raise
            pl.infeasible.append(str(exc))
            gone = set(exc.contingencies)
            pl.set_aside.extend(sorted(gone))
            rounds.append({"round": rnd, "active": [c.name for c in active],
                           "total_mw": None, "set_aside": sorted(gone), "failing": [],
                           "iterations": 0})
            pl.say(f"round {rnd}: set aside as infeasible: {', '.join(sorted(gone))}")
            cons = tuple(c for c in cons if c.name not in gone)
            active = [c for c in active if c.name not in gone]
            evs = {k: v for k, v in evs.items() if k not in gone}
            if active:
                continue
            res = None
        if res is None:             # nothing left to solve for: check the allocation
            checks = pl.check(cons, mw)
            fails = [c for c in cons if not checks[c.name]["stable_at_check"]]
            if not fails:
                verified, message = True, f"verified on every contingency after {rnd} round(s)"
                break
            active = _most_binding(fails, brackets, base, n_active)
            base.update(_base(pl, [c for c in active if c.name not in base], brackets, kw))
            continue
        mw, evs = res.allocation.mw, dict(res.evaluations)
        checks = pl.check(cons, mw)
        fails = [c for c in cons if not checks[c.name]["stable_at_check"]]
        rounds.append({"round": rnd, "active": [c.name for c in active],
                       "total_mw": float(mw.sum()), "loop_verified": res.verified,
                       "loop_message": res.message, "failing": [c.name for c in fails],
                       "iterations": len(res.iterations)})
        pl.say(f"round {rnd}: {mw.sum():.1f} MW, checked {len(cons)} contingencies: "
               + (f"{len(fails)} fail (" + ", ".join(c.name for c in fails[:8]) + ")"
                  if fails else "all stable"))
        if not res.verified:
            message = f"round {rnd}: the loop did not verify an allocation ({res.message})"
            verified = False
            break
        if not fails:
            verified, message = True, f"verified on every contingency after {rnd} round(s)"
            break
        new = [c for c in fails if c.name not in {a.name for a in active}]
        if not new:
            verified = False
            message = (f"round {rnd}: contingencies of the active set fail their check "
                       f"run: {', '.join(c.name for c in fails)}")
            break
        base.update(_base(pl, [c for c in new if c.name not in base], brackets, kw))
        active = active + new
    mwh, energy, ok = _size_energy(pl, cons, mw, checks)
    if verified and not ok:
        verified, message = False, message + "; the sized energies fail a check run"
    return PlanResult(case=pl.case, requirement="", load_levels=(), sites=pl.sites, mw=mw,
                      mwh=mwh, cost=pl.cost.split(pl.sites, mw, mwh), verified=verified,
                      contingencies=_rows(cons, checks, evs, base), rounds=rounds,
                      active=[c.name for c in active], message=message, energy=energy)


def _energy_need(check: dict, k: int) -> float:
    """Energy need (MWh) of the k-th site with storage in a check run: twice its largest
    state-of-charge excursion (a device started half full)."""
    _, _, hi, lo = check["energy_mj"][k]
    return 2 * max(hi, -lo) / 3600


def _size_energy(pl: _Plan, cons, mw, checks) -> tuple:
    """Usable energy per site (MWh) from the check runs at ratings mw: twice the largest
    state-of-charge excursion (device started half full) plus ENERGY_MARGIN, rounded up
    to 0.01 MWh; the runs that set it simulated again with that finite energy.
    Returns (mwh (n_sites,), per-site energy figures, all those runs stable)."""
    used = [j for j, p in enumerate(mw) if p > 0]
    n = len(pl.sites)
    mwh, energy = np.zeros(n), [{} for _ in range(n)]
    if not used:
        return mwh, energy, True
    setter = {}
    for c in cons:
        for k, j in enumerate(used):
            a, d, _, _ = checks[c.name]["energy_mj"][k]
            need = _energy_need(checks[c.name], k)
            e = energy[j]
            e["absorbed_mj"] = max(e.get("absorbed_mj", 0.0), a)
            e["delivered_mj"] = max(e.get("delivered_mj", 0.0), d)
            if need >= mwh[j]:
                mwh[j], setter[j] = need, c
                e["excursion_mwh"] = need
    mwh = np.where(mw > 0, np.ceil(100 * (1 + ENERGY_MARGIN) * mwh - 1e-9) / 100, 0.0)
    mwh = np.where(mw > 0, np.maximum(mwh, 0.01), 0.0)
    for j in used:
        energy[j]["set_by"] = setter[j].name
    again = _energy_setters({c.name: c for c in cons}, mw, energy)
    rerun = pl.check(again, mw, energy_mj=3600 * mwh)
    ok = all(r["stable_at_check"] for r in rerun.values())
    pl.say(f"energy: {mwh.sum():.2f} MWh at {len(used)} site(s); {len(again)} run(s) "
           f"again with that energy: {'stable' if ok else 'UNSTABLE'}")
    return mwh, energy, ok


def _rows(cons, checks, evs, base) -> list:
    """One row per contingency: name, fault, load, required time, stable at it, CCT
    without storage and with the allocation where simulated, margin (s)."""
    out = []
    for c in cons:
        cct = evs.get(c.name, {}).get("cct_s")
        out.append({"name": c.name, "fault": c.fault.describe(), "fault_name": c.fault_name,
                    "load": c.load, "required_s": c.target_cct_s,
                    "met": bool(checks[c.name]["stable_at_check"])
                    and (cct is None or cct >= c.target_cct_s - 1e-9),
                    "cct_no_storage_s": base.get(c.name, {}).get("cct_s"),
                    "cct_s": cct, "margin_s": None if cct is None else cct - c.target_cct_s,
                    "margin_at_least": False})
    return out


class _Heartbeat:
    """progress(str) as a callable that also repeats the latest status (`note`) whenever
    nothing was said for HEARTBEAT_S (a thread), so that long batches are never silent."""

    def __init__(self, progress):
        import threading

        self._say = progress
        self.status, self.last = "", time.monotonic()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)

    def __enter__(self):
        if self._say is not None:
            self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()

    def __call__(self, msg: str) -> None:
        self.last = time.monotonic()
        if self._say is not None:
            self._say(msg)

    def note(self, status: str) -> None:
        self.status = status

    def _loop(self):
        while not self._stop.wait(0.5):
            if self.status and time.monotonic() - self.last >= HEARTBEAT_S:
                self(f"... {self.status}")


def margins(pl: _Plan, cons, result: PlanResult, tol: float, cap_s: float, kw) -> None:
    """Fill the CCT and margin of every contingency row without one (those only checked
    at their required time T): a run cleared at T + cap_s; stable there, the margin is
    reported as at least cap_s (``margin_at_least``); otherwise a bisection with the
    allocation between T (stable, its check) and T + cap_s to `tol` (s), no gradient
    runs (`critical_clearing_time`)."""
    rows = {r["name"]: r for r in result.contingencies}
    todo = [c for c in cons if rows[c.name]["cct_s"] is None and rows[c.name]["met"]]
    if not todo:
        return
    pl.say(f"clearing margins of {len(todo)} contingencies (up to {1000 * cap_s:g} ms, "
           f"{1000 * tol:g} ms)")
    top = {c.name: round(min(c.target_cct_s + cap_s, pl.t_max), 12) for c in todo}
    far = pl.check([replace(c, target_cct_s=top[c.name]) for c in todo], result.mw)
    near = [c for c in todo if not far[c.name]["stable_at_check"]]
    for c in todo:
        if far[c.name]["stable_at_check"]:
            rows[c.name].update(margin_s=top[c.name] - c.target_cct_s, margin_at_least=True)
    if not near:
        return
    ev = evaluations(pl.case, near, result.mw, gradient=False,
                     brackets={c.name: (c.target_cct_s, top[c.name]) for c in near},
                     **{**kw, "tol": tol})
    for c in near:
        rows[c.name].update(cct_s=ev[c.name]["cct_s"], cct_tol_s=tol,
                            margin_s=ev[c.name]["cct_s"] - c.target_cct_s)


def half_step(pl: _Plan, cons, result: PlanResult, n: int, kw) -> dict:
    """The allocation's n contingencies of least clearing margin (those with a simulated
    CCT) simulated again at half the integration step: each cleared at its required time
    (the verdict), and its CCT with the allocation to the plan's tolerance, the bisection
    starting from two tolerances either side of the CCT at the full step (shown converged
    in the step, as every figure that depends on it).

    The runs that set each site's energy (`_size_energy`) are simulated again at half the
    step too: the energy is shown converged in the step as well.

    Returns {"h_s" (the full step, s), "rows": [{"name", "required_s", "cct_s" (full
    step), "cct_tol_s" (its resolution), "cct_half_s", "stable_half" (at the required
    time)}], "all_stable", "max_cct_diff_s" (largest |cct_half - cct| beyond the coarser
    resolution, s), and the energy's half-step figures (`_energy_half_step`)}."""
    h = _step_s(pl)
    by_name = {c.name: c for c in cons}
    rows = sorted((r for r in result.contingencies if r["cct_s"] is not None),
                  key=lambda r: r["margin_s"])[:n]
    tight = [by_name[r["name"]] for r in rows]
    res_of = {r["name"]: r.get("cct_tol_s", pl.tol) for r in rows}
    # one batch: the tightest contingencies and those that set an energy (often the same)
    setters = _energy_setters(by_name, result.mw, result.energy)
    checks = pl.check(list({c.name: c for c in tight + setters}.values()), result.mw,
                      h=h / 2)
    ev = evaluations(pl.case, tight, result.mw, gradient=False,
                     brackets={r["name"]: (r["cct_s"] - 2 * res_of[r["name"]],
                                          r["cct_s"] + 2 * res_of[r["name"]]) for r in rows},
                     **{**kw, "h": h / 2})
    out = [{"name": r["name"], "required_s": r["required_s"], "cct_s": r["cct_s"],
            "cct_tol_s": res_of[r["name"]], "cct_half_s": ev[r["name"]]["cct_s"],
            "stable_half": bool(checks[r["name"]]["stable_at_check"])} for r in rows]
    diff = max((max(0.0, abs(o["cct_half_s"] - o["cct_s"]) - o["cct_tol_s"]) for o in out),
               default=0.0)
    ok = all(o["stable_half"] for o in out)
    energy = _energy_half_step(checks, result.mw, result.mwh, result.energy)
    pl.say(f"half step ({1000 * h / 2:.3g} ms): {len(out)} tightest contingencies "
           f"{'all stable' if ok else 'NOT all stable'} at their required time; CCTs within "
           f"{1000 * diff:.0f} ms beyond their resolution" + _energy_note(energy))
    return {"h_s": h, "rows": out, "all_stable": ok, "max_cct_diff_s": diff, **energy}


def _step_s(pl: _Plan) -> float:
    """The integration step of the plan's runs (s)."""
    from stabctl.stability.cct import cached_simulator

    return cached_simulator(pl.case, ModelOptions.from_inputs(pl.model)).default_h \
        if pl.model["h"] is None else pl.model["h"]


def _energy_setters(by_name: dict, mw, energy) -> list:
    """The contingencies whose check runs set a site's energy (`_size_energy`), each once,
    in name order."""
    return [by_name[n] for n in sorted({energy[j]["set_by"] for j, p in enumerate(mw)
                                        if p > 0})]


def _energy_half_step(checks: dict, mw, mwh, energy) -> dict:
    """The sized energies against `checks`, the runs that set them (`_size_energy`)
    simulated again at half the step: {"max_energy_diff_mwh" (largest change of a site's
    energy need, `_energy_need`, MWh), "max_energy_diff_pct" (the largest change relative
    to that site's need, %), "energy_covered_half" (every site's sized energy, margin and
    rounding included, at least its need at half the step)}; None each without sites (the
    percentage also when no site needed any energy at the full step)."""
    used = [j for j, p in enumerate(mw) if p > 0]
    if not used:
        return {"max_energy_diff_mwh": None, "max_energy_diff_pct": None,
                "energy_covered_half": None}
    half = {j: _energy_need(checks[energy[j]["set_by"]], k) for k, j in enumerate(used)}
    diff = {j: abs(half[j] - energy[j]["excursion_mwh"]) for j in used}
    return {"max_energy_diff_mwh": max(diff.values()),
            "max_energy_diff_pct": max((100 * diff[j] / energy[j]["excursion_mwh"]
                                        for j in used if energy[j]["excursion_mwh"] > 0),
                                       default=None),
            "energy_covered_half": all(half[j] <= mwh[j] for j in used)}


def _energy_note(e: dict) -> str:
    """Progress text of `_energy_half_step`'s figures ('' without sites)."""
    if e["max_energy_diff_mwh"] is None:
        return ""
    pct = e["max_energy_diff_pct"]
    return (f"; energies within {e['max_energy_diff_mwh']:.3f} MWh"
            + ("" if pct is None else f" ({pct:.1f} %)") + " at half the step, "
            + ("covered by the sizing" if e["energy_covered_half"] else "NOT covered"))


# -- references ------------------------------------------------------------------------------

def least_uniform(pl: _Plan, cons, failing, kw) -> dict:
    """The least uniform fleet (the same % of MVA at every generator, rounded up to 0.1 MW
    per site) meeting every contingency: bisection on the % (to UNIFORM_RES_PCT) with
    the check runs of the contingencies that fail without storage, then every
    contingency checked at the result and those failing without storage verified by
    their first unstable clearing time, as the active set of `plan`; a miss there moves
    the % up one resolution step and checks again.  The runs that set each site's energy
    are simulated again at half the step (shown converged, as the optimised allocation's
    in `half_step`).  Returns {"pct" (%), "total_mw", "mw_by_site" (MW), "mwh", "cost"
    (`CostModel.split`), "verified", "energy" (per site, as `PlanResult.energy`), and the
    energy's half-step figures (`_energy_half_step`)}; pct None
    and verified False when even the site bounds fail."""
    mva = _mva(pl)
    upper = np.array([s.max_mw for s in pl.sites])
    pct_max = float(np.min(100 * upper / mva))
    fleet = lambda p: _rounded(np.minimum(p / 100 * mva, upper), pl.sites)  # noqa: E731
    if not failing:
        return {"pct": 0.0, "total_mw": 0.0, "mwh": 0.0, "cost": pl.cost.split(
            pl.sites, np.zeros(len(mva)), np.zeros(len(mva))), "verified": True}

    def meets(p, which):
        ck = pl.check(which, fleet(p))
        return all(r["stable_at_check"] for r in ck.values()), ck

    lo, hi = 0.0, min(5.0, pct_max)
    while not meets(hi, failing)[0]:
        if hi >= pct_max:
            pl.say(f"uniform: not met even at {pct_max:g} % of every MVA")
            return {"pct": None, "total_mw": None, "verified": False}
        lo, hi = hi, min(2 * hi, pct_max)
    while hi - lo > UNIFORM_RES_PCT + 1e-9:
        mid = round(0.5 * (lo + hi), 6)
        lo, hi = (lo, mid) if meets(mid, failing)[0] else (mid, hi)
    hi = float(np.ceil(hi / UNIFORM_RES_PCT - 1e-6) * UNIFORM_RES_PCT)
    pl.say(f"uniform: {hi:g} % meets the contingencies unstable without storage; "
           "checking every contingency")
    while True:
        ok, ck = meets(hi, cons)
        if ok:
            pl.base.update(_base(pl, [c for c in failing if c.name not in pl.base],
                                 pl.brackets, kw))
            ev = evaluations(pl.case, failing, fleet(hi), base=pl.base, **kw)
            ok = all(ev[c.name]["cct_s"] >= c.target_cct_s - 1e-9 for c in failing)
        if ok or hi >= pct_max:
            break
        hi = round(hi + UNIFORM_RES_PCT, 6)
    mw = fleet(hi)
    mwh, energy, e_ok = _size_energy(pl, cons, mw, ck)
    setters = _energy_setters({c.name: c for c in cons}, mw, energy)
    half = _energy_half_step(pl.check(setters, mw, h=_step_s(pl) / 2), mw, mwh, energy)
    pl.say(f"uniform: {hi:g} % = {mw.sum():.0f} MW, "
           f"{'verified' if ok and e_ok else 'NOT verified'}" + _energy_note(half))
    return {"pct": hi, "total_mw": float(mw.sum()), "mw_by_site": mw.tolist(),
            "mwh": float(mwh.sum()), "cost": pl.cost.split(pl.sites, mw, mwh),
            "verified": bool(ok and e_ok), "energy": energy, **half}


def _mva(pl: _Plan) -> np.ndarray:
    from stabctl.stability.cct import cached_simulator

    case = cached_simulator(pl.case, ModelOptions.from_inputs(pl.model)).case
    return np.array([float(case.machines.mva[case.machine_index(s.machine)])
                     for s in pl.sites])


def _alone(pl: _Plan, cons, result: PlanResult, max_iter: int, kw) -> list:
    """Each fault of the final active set alone (all its load levels that fail without
    storage): its own least allocation, verified by `place` (MW, sites, verified).  The
    faults are solved at the same time (one thread each, sharing the worker pool: a
    single fault's batches are too small to keep every worker busy)."""
    from concurrent.futures import ThreadPoolExecutor

    by_name = {c.name: c for c in cons}
    faults = list(dict.fromkeys(by_name[n].fault_name for n in result.active))
    if not faults:
        return []
    sites = pl.priced(pl.energy_rate)

    def one(fname):
        mine = [by_name[n] for n in result.active if by_name[n].fault_name == fname]
        base = {c.name: pl.base[c.name] for c in mine}
        try:
            res = place(pl.case, mine, base=base, max_iter=max_iter,
                        site_cost=pl.site_costs, **{**kw, "sites": sites})
        except InfeasibleError as exc:
            return {"fault": fname, "total_mw": None, "verified": False, "message": str(exc)}
        pl.say(f"alone: {fname}: {res.allocation.total_mw:.1f} MW")
        return {"fault": fname, "contingencies": [c.name for c in mine],
                "total_mw": res.allocation.total_mw, "allocation": res.allocation.rows(),
                "verified": res.verified}

    with ThreadPoolExecutor(max_workers=len(faults)) as threads:
        return list(threads.map(one, faults))
