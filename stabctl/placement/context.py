"""What every step of a plan shares (`PlanContext`): the case, candidate sites, costs,
controller and model settings, the worker map that counts the simulations, what is known
without storage, and the check runs (docs/placement.md, section 7).  Used by the
constraint generation (`stabctl.placement.plan`), the energy sizing
(`stabctl.placement.energy`) and the references (`stabctl.placement.references`).
"""

from __future__ import annotations

import functools
import inspect
import threading
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from tqdm import tqdm

from stabctl.dynamics.options import ModelOptions
from stabctl.errors import InsecureContingency
from stabctl.placement.evaluation import (
    VerifyOptions,
    check,
    controller_dict,
    devices_of,
    run_end,
    simulable,
)
from stabctl.placement.loop import PlaceOptions, Study, evaluations
from stabctl.placement.requirements import CostModel
from stabctl.progress import BatchClock
from stabctl.stability.cct import cached_simulator, fault_inputs
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import model_inputs


@dataclass
class PlanContext:
    """What every round of a plan needs.

    case: case name; sites: candidate sites; cost: `CostModel`; controller: the ESD
    controller; model: `ModelOptions` of the runs; run_map: callable(func, jobs) ->
    results (`counting`); tol, t_max: CCT tolerance and search limit (s); say: progress
    callable (`stabctl.progress.Heartbeat`); n_runs: simulations counted; base: name ->
    evaluation without storage (`add_base`); energy_rate: usable energy per MW at each site (MWh/MW,
    `stabctl.placement.energy.mwh_per_mw`); drop_infeasible, brackets: as `plan`;
    infeasible, set_aside: what was set aside as infeasible; not_simulable: name -> why
    of the contingencies set aside as not simulable (`simulable`); n1_insecure: name ->
    the verdict of those set aside as N-1 insecure (`add_base`); place: the
    `PlaceOptions` of every round's `place` (damping, sparsity, iterations); esd_model:
    the devices' model (`Study.esd_model`); critical_reference: the law armed per
    contingency (`Study.critical_reference`).
    """

    case: str
    sites: tuple
    cost: CostModel
    controller: BangBangCOI
    model: ModelOptions
    run_map: Any
    tol: float
    t_max: float
    say: Any
    n_runs: int = 0
    base: dict = field(default_factory=dict)
    energy_rate: np.ndarray | None = None
    drop_infeasible: bool = False
    brackets: dict | None = None
    infeasible: list = field(default_factory=list)
    set_aside: list = field(default_factory=list)
    not_simulable: dict = field(default_factory=dict)
    n1_insecure: dict = field(default_factory=dict)
    place: PlaceOptions = PlaceOptions()
    esd_model: str = "ideal"
    critical_reference: bool = False
    lock: Any = field(default_factory=threading.Lock)
    started: float = field(default_factory=time.monotonic)

    @functools.cached_property
    def case_digest(self) -> str:
        """The digest of the case's content as the plan first read it, put in every job
        (checked where it runs: `stabctl.stability.cct.job_case`: a file edited during
        the plan stops it rather than mixing two cases)."""
        return cached_simulator(self.case, self.model).case.digest()

    def check(
        self, contingencies, mw, energy_mj=None, h: float | None = None, longer: bool = False
    ) -> dict:
        """`stabctl.placement.evaluation.check` of every contingency at ratings mw (one
        run each, in parallel): name -> check dict.  energy_mj: usable energy per site
        (MJ) of finite devices; h: another integration step (s) than the plan's; longer:
        each run again T_AFTER_FAULT s longer instead (`stabctl.placement.evaluation.
        run_end`: name -> {"t_end_s", "t_separation_s"}, s)."""
        devs = devices_of(self.sites, mw)
        if energy_mj is not None:
            used = [j for j, p in enumerate(mw) if p > 0]
            devs = [d + [float(energy_mj[j])] for d, j in zip(devs, used)]
        ctrl = controller_dict(
            self.controller,
            {"tol": self.tol, "t_max": self.t_max} if self.critical_reference else None,
        )
        sites = [[s.bus, s.machine] for s in self.sites]
        jobs = [
            {
                "case": self.case,
                "case_digest": self.case_digest,
                "fault": fault_inputs(c.fault),
                "devices": devs,
                "sites": sites,
                "controller": ctrl,
                "t_clear": c.target_cct_s,
                "load": c.load,
                **self.model.to_inputs(),
                **model_inputs(self.esd_model),
                **({} if h is None else {"h": h}),
            }
            for c in contingencies
        ]
        out = self.run_map(run_end if longer else check, jobs)
        return dict(zip((c.name for c in contingencies), out))

    def simulable(self, contingencies) -> tuple:
        """The contingencies whose fault can be simulated without storage while it is on
        for up to the search limit (`stabctl.placement.evaluation.simulable`, one short
        run each, in parallel); the others go to `not_simulable` with the failure's
        message."""
        jobs = [
            {
                "case": self.case,
                "case_digest": self.case_digest,
                "fault": fault_inputs(c.fault),
                "t_max": self.t_max,
                "load": c.load,
                **self.model.to_inputs(),
            }
            for c in contingencies
        ]
        out = self.run_map(simulable, jobs)
        for c, o in zip(contingencies, out):
            if o["failure"] is not None:
                self.not_simulable[c.name] = o["failure"]
        return tuple(c for c in contingencies if c.name not in self.not_simulable)

    def priced(self, mwh_per_mw) -> tuple:
        """Sites whose cost per MW includes their energy at mwh_per_mw (MWh/MW)."""
        return tuple(
            replace(s, cost=max(self.cost.of(s.machine)[0] + self.cost.of(s.machine)[1] * e, 1e-9))
            for s, e in zip(self.sites, mwh_per_mw)
        )

    def counting(self, run_map, beat):
        """run_map that adds the simulations its jobs report to n_runs and tells the
        heartbeat `beat` how far each batch is (`stabctl.progress.BatchClock`: jobs done
        of the batch's and the time left, worked out at each repeat, when run_map takes
        ``done``, as `stabctl.parallel.worker_pool`'s does) and when the batch was handed
        in, into the plan (its rounds and iterations are bounded where each round
        starts: `stabctl.placement.plan`), repeated while nothing else is said."""

        def counted(func, jobs):
            ran = tqdm.format_interval(time.monotonic() - self.started)
            before = (
                f"the batch handed in {ran} into the plan, {self.n_runs} runs simulated before it"
            )
            clock = BatchClock(len(jobs))
            beat.note(lambda: f"{func.__name__}: {clock.line()}; {before}")
            takes_done = "done" in inspect.signature(run_map).parameters
            out = run_map(func, jobs, done=clock.done) if takes_done else run_map(func, jobs)
            with self.lock:  # `faults_alone` runs batches from several threads
                self.n_runs += sum(o.get("n_simulations") or 0 for o in out)
            return out

        return counted

    @property
    def site_costs(self) -> np.ndarray:
        """Cost per site (installed or not) at each candidate, (n_sites,)."""
        return np.array([self.cost.of(s.machine)[2] for s in self.sites])

    def add_base(self, cons, brackets, study: Study) -> None:
        """Add to `base` the evaluations without storage (CCT by bisection, from the
        screening's bracket when known, and its gradient; counted) of the contingencies
        of `cons` it lacks (`stabctl.placement.loop.evaluations` of `study`).
        brackets: fault name -> [stable, unstable] clearing times (s), or None.  A
        contingency N-1 insecure (unstable even when cleared at once: the CCT search's
        verdict) goes to `n1_insecure` when the plan sets infeasible ones aside (its
        callers leave it out: `planned`); else it is raised.

        Raises
        ------
        InsecureContingency
            An N-1 insecure contingency, the plan not setting any aside (the first, named,
            and how to set it aside).
        """
        todo = [c for c in cons if c.name not in self.base]
        if not todo:
            return
        br = {
            c.name: tuple(brackets[c.fault_name])
            for c in todo
            if brackets
            and c.load == 1.0
            and c.fault_name in brackets
            and None not in brackets[c.fault_name]
        }
        got = evaluations(
            self.case, todo, None, study, VerifyOptions(brackets=br, insecure_verdict=True)
        )
        insecure = {n: e["n1_insecure"] for n, e in got.items() if "n1_insecure" in e}
        if insecure and not self.drop_infeasible:
            name, why = next(iter(insecure.items()))
            raise InsecureContingency(
                f"contingency {name}: {why} (--set-aside-infeasible, PlanOptions."
                "drop_infeasible, sets it aside, listed as N-1 insecure, and plans for the "
                "others)"
            )
        for name, why in insecure.items():
            if name not in self.n1_insecure:
                self.n1_insecure[name] = why
                self.say(f"set aside as N-1 insecure: {name}: {why}")
        self.base.update({n: e for n, e in got.items() if n not in insecure})

    def planned(self, cons) -> tuple:
        """The contingencies of `cons` not set aside as N-1 insecure (`add_base`)."""
        return tuple(c for c in cons if c.name not in self.n1_insecure)

    def step_s(self) -> float:
        """The integration step of the plan's runs (s)."""
        if self.model.h is not None:
            return self.model.h
        return cached_simulator(self.case, self.model).default_h
